#include "kinect_streams.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "rgbdmap/drivers/oni_property.hpp"

namespace rgbdmap::openni2_freenect {
namespace {

constexpr int kWidth = KinectV1Model::kWidth;
constexpr int kHeight = KinectV1Model::kHeight;

OniVideoMode mode(OniPixelFormat format) {
  OniVideoMode m{};
  m.pixelFormat = format;
  m.resolutionX = kWidth;
  m.resolutionY = kHeight;
  m.fps = kFps;
  return m;
}

int bytesPerPixel(OniPixelFormat format) { return format == ONI_PIXEL_FORMAT_RGB888 ? 3 : 2; }

std::uint64_t nowMicroseconds() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

}  // namespace

KinectStream::KinectStream(OniSensorType type, std::vector<OniVideoMode> modes, StreamHost& host)
    : type_(type), modes_(std::move(modes)), host_(host), mode_(modes_.front()) {}

std::vector<OniVideoMode> KinectStream::depthModes() {
  return {mode(ONI_PIXEL_FORMAT_DEPTH_1_MM), mode(ONI_PIXEL_FORMAT_DEPTH_100_UM)};
}

std::vector<OniVideoMode> KinectStream::colorModes() { return {mode(ONI_PIXEL_FORMAT_RGB888)}; }

OniStatus KinectStream::start() {
  if (!host_.streamStarted(type_)) return ONI_STATUS_ERROR;
  std::lock_guard<std::mutex> lock(mutex_);
  started_ = true;
  return ONI_STATUS_OK;
}

void KinectStream::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!started_) return;
    started_ = false;
  }
  host_.streamStopped(type_);
}

OniStatus KinectStream::setProperty(int property, const void* data, int size) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (property == ONI_STREAM_PROPERTY_VIDEO_MODE) {
    OniVideoMode wanted{};
    if (const OniStatus status = readProperty(data, size, wanted); status != ONI_STATUS_OK)
      return status;
    for (const OniVideoMode& m : modes_)
      if (m.pixelFormat == wanted.pixelFormat && m.resolutionX == wanted.resolutionX &&
          m.resolutionY == wanted.resolutionY && m.fps == wanted.fps) {
        mode_ = m;
        return ONI_STATUS_OK;
      }
    return ONI_STATUS_NOT_SUPPORTED;
  }
  if (property == ONI_STREAM_PROPERTY_MIRRORING) {
    OniBool mirroring = FALSE;
    if (const OniStatus status = readProperty(data, size, mirroring); status != ONI_STATUS_OK)
      return status;
    mirroring_ = mirroring != FALSE;
    return ONI_STATUS_OK;
  }
  return isPropertySupported(property) ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_NOT_IMPLEMENTED;
}

OniStatus KinectStream::getProperty(int property, void* data, int* size) {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (property) {
    case ONI_STREAM_PROPERTY_VIDEO_MODE:
      return writeProperty(data, size, mode_);
    case ONI_STREAM_PROPERTY_MIRRORING:
      return writeProperty(data, size, static_cast<OniBool>(mirroring_ ? TRUE : FALSE));
    case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:  // the colour camera's (depth is registered to it)
      return writeProperty(data, size,
                           static_cast<float>(2 * std::atan(kWidth / (2 * KinectV1Model::kFocal))));
    case ONI_STREAM_PROPERTY_VERTICAL_FOV:
      return writeProperty(
          data, size, static_cast<float>(2 * std::atan(kHeight / (2 * KinectV1Model::kFocal))));
    case ONI_STREAM_PROPERTY_STRIDE:
      return writeProperty(data, size, kWidth * bytesPerPixel(mode_.pixelFormat));
    default:
      return ONI_STATUS_NOT_IMPLEMENTED;
  }
}

OniBool KinectStream::isPropertySupported(int property) {
  switch (property) {
    case ONI_STREAM_PROPERTY_VIDEO_MODE:
    case ONI_STREAM_PROPERTY_MIRRORING:
    case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
    case ONI_STREAM_PROPERTY_VERTICAL_FOV:
    case ONI_STREAM_PROPERTY_STRIDE:
      return TRUE;
    default:
      return FALSE;
  }
}

// The whole frame, header included, is written uninstrumented (see KINECT_WRITES_OPENNI2_FRAMES);
// the mutex still orders it with property changes for ThreadSanitizer.
template <typename Write>
KINECT_WRITES_OPENNI2_FRAMES void KinectStream::deliver(Write&& write) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!started_) return;
  OniFrame* frame = getServices().acquireFrame();
  if (frame == nullptr) return;
  frame->frameIndex = ++frame_index_;
  frame->timestamp = nowMicroseconds();
  frame->videoMode = mode_;
  frame->width = kWidth;
  frame->height = kHeight;
  frame->cropOriginX = 0;
  frame->cropOriginY = 0;
  frame->croppingEnabled = FALSE;
  frame->sensorType = type_;
  frame->stride = kWidth * bytesPerPixel(mode_.pixelFormat);
  write(frame, mode_, mirroring_);
  raiseNewFrame(frame);
  getServices().releaseFrame(frame);
}

KinectDepthStream::KinectDepthStream(StreamHost& host, const KinectV1Model& model)
    : KinectStream(ONI_SENSOR_DEPTH, depthModes(), host),
      model_(model),
      registered_(static_cast<std::size_t>(kWidth) * kHeight) {}

KINECT_WRITES_OPENNI2_FRAMES static void writeDepth(OniFrame* frame, const std::uint16_t* raw,
                                                    const KinectV1Model& model,
                                                    const OniVideoMode& mode, bool mirroring) {
  const double units_per_metre = mode.pixelFormat == ONI_PIXEL_FORMAT_DEPTH_100_UM ? 1e4 : 1e3;
  auto* out = static_cast<std::uint16_t*>(frame->data);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const double metres = model.metres(raw[y * kWidth + x]);
      const double units = std::round(metres * units_per_metre);
      const int target = mirroring ? kWidth - 1 - x : x;
      out[y * kWidth + target] = units > 65535 ? 0 : static_cast<std::uint16_t>(units);
    }
}

void KinectDepthStream::deliverRaw(const std::uint16_t* raw) {
  const bool registered = host_.registered();
  if (registered) model_.registerToColour(raw, registered_.data());
  const std::uint16_t* source = registered ? registered_.data() : raw;
  deliver([&](OniFrame* frame, const OniVideoMode& mode, bool mirroring) {
    writeDepth(frame, source, model_, mode, mirroring);
  });
}

KinectColorStream::KinectColorStream(StreamHost& host)
    : KinectStream(ONI_SENSOR_COLOR, colorModes(), host) {}

KINECT_WRITES_OPENNI2_FRAMES static void writeColor(OniFrame* frame, const std::uint8_t* rgb,
                                                    bool mirroring) {
  auto* out = static_cast<std::uint8_t*>(frame->data);
  if (!mirroring) {
    std::memcpy(out, rgb, static_cast<std::size_t>(kWidth) * kHeight * 3);
    return;
  }
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      std::memcpy(out + (y * kWidth + (kWidth - 1 - x)) * 3, rgb + (y * kWidth + x) * 3, 3);
}

void KinectColorStream::deliverRgb(const std::uint8_t* rgb) {
  deliver([&](OniFrame* frame, const OniVideoMode&, bool mirroring) {
    writeColor(frame, rgb, mirroring);
  });
}

}  // namespace rgbdmap::openni2_freenect
