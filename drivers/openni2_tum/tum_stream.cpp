#include "tum_stream.hpp"

#include <algorithm>
#include <utility>

#include "camera_presets.hpp"
#include "driver_log.hpp"
#include "rgbdmap/drivers/oni_property.hpp"

namespace rgbdmap::openni2_tum {

int bytesPerPixel(OniPixelFormat format) {
  switch (format) {
    case ONI_PIXEL_FORMAT_DEPTH_1_MM:
    case ONI_PIXEL_FORMAT_DEPTH_100_UM:
      return 2;
    case ONI_PIXEL_FORMAT_RGB888:
      return 3;
    default:
      return 0;
  }
}

TumStream::TumStream(OniSensorType type, std::vector<OniVideoMode> modes,
                     const CameraIntrinsics& intrinsics, StreamHost& host, DriverLog& log)
    : intrinsics_(intrinsics),
      type_(type),
      modes_(std::move(modes)),
      host_(host),
      log_(log),
      mode_(modes_.front()) {}

// The host is told under the stream's mutex so that its count of running streams always
// matches; the device's playback thread never takes a stream's mutex while holding its own.
OniStatus TumStream::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (started_) return ONI_STATUS_OK;
  if (!host_.streamStarted()) return ONI_STATUS_ERROR;
  started_ = true;
  return ONI_STATUS_OK;
}

void TumStream::stop() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!started_) return;
  started_ = false;
  host_.streamStopped();
}

int TumStream::getRequiredFrameSize() {
  // The largest any mode needs: OpenNI2 may size its frame pool before a mode change.
  int largest = 0;
  for (const OniVideoMode& mode : modes_)
    largest =
        std::max(largest, mode.resolutionX * mode.resolutionY * bytesPerPixel(mode.pixelFormat));
  return largest;
}

cv::Rect TumStream::deliveredRect() const {
  if (!cropping_.enabled) return cv::Rect(0, 0, mode_.resolutionX, mode_.resolutionY);
  return cv::Rect(cropping_.originX, cropping_.originY, cropping_.width, cropping_.height);
}

OniStatus TumStream::setProperty(int property, const void* data, int size) {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (property) {
    case ONI_STREAM_PROPERTY_VIDEO_MODE: {
      OniVideoMode mode;
      if (const OniStatus status = readProperty(data, size, mode); status != ONI_STATUS_OK)
        return status;
      const auto same = [&mode](const OniVideoMode& m) {
        return m.pixelFormat == mode.pixelFormat && m.resolutionX == mode.resolutionX &&
               m.resolutionY == mode.resolutionY && m.fps == mode.fps;
      };
      if (std::none_of(modes_.begin(), modes_.end(), same)) return ONI_STATUS_NOT_SUPPORTED;
      mode_ = mode;
      return ONI_STATUS_OK;
    }
    case ONI_STREAM_PROPERTY_CROPPING: {
      OniCropping cropping;
      if (const OniStatus status = readProperty(data, size, cropping); status != ONI_STATUS_OK)
        return status;
      if (!cropping.enabled) {
        cropping_ = OniCropping{};
        return ONI_STATUS_OK;
      }
      if (cropping.originX < 0 || cropping.originY < 0 || cropping.width <= 0 ||
          cropping.height <= 0 || cropping.originX + cropping.width > mode_.resolutionX ||
          cropping.originY + cropping.height > mode_.resolutionY)
        return ONI_STATUS_BAD_PARAMETER;
      cropping_ = cropping;
      cropping_.enabled = TRUE;
      return ONI_STATUS_OK;
    }
    case ONI_STREAM_PROPERTY_MIRRORING: {
      OniBool mirroring;
      if (const OniStatus status = readProperty(data, size, mirroring); status != ONI_STATUS_OK)
        return status;
      mirroring_ = mirroring != FALSE;
      return ONI_STATUS_OK;
    }
    default:
      return isPropertySupported(property) ? ONI_STATUS_NOT_SUPPORTED  // read-only
                                           : ONI_STATUS_NOT_IMPLEMENTED;
  }
}

OniStatus TumStream::getProperty(int property, void* data, int* size) {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (property) {
    case ONI_STREAM_PROPERTY_VIDEO_MODE:
      return writeProperty(data, size, mode_);
    case ONI_STREAM_PROPERTY_CROPPING:
      return writeProperty(data, size, cropping_);
    case ONI_STREAM_PROPERTY_MIRRORING:
      return writeProperty(data, size, static_cast<OniBool>(mirroring_ ? TRUE : FALSE));
    case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
      return writeProperty(data, size,
                           static_cast<float>(fieldOfView(intrinsics_.width, intrinsics_.fx)));
    case ONI_STREAM_PROPERTY_VERTICAL_FOV:
      return writeProperty(data, size,
                           static_cast<float>(fieldOfView(intrinsics_.height, intrinsics_.fy)));
    case ONI_STREAM_PROPERTY_STRIDE:
      return writeProperty(data, size, deliveredRect().width * bytesPerPixel(mode_.pixelFormat));
    case ONI_STREAM_PROPERTY_NUMBER_OF_FRAMES:
      if (host_.recordedFrames() <= 0) return ONI_STATUS_NOT_IMPLEMENTED;
      return writeProperty(data, size, host_.recordedFrames());
    default:
      return getOwnProperty(property, data, size, mode_);
  }
}

OniBool TumStream::isPropertySupported(int property) {
  switch (property) {
    case ONI_STREAM_PROPERTY_VIDEO_MODE:
    case ONI_STREAM_PROPERTY_CROPPING:
    case ONI_STREAM_PROPERTY_MIRRORING:
    case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
    case ONI_STREAM_PROPERTY_VERTICAL_FOV:
    case ONI_STREAM_PROPERTY_STRIDE:
      return TRUE;
    case ONI_STREAM_PROPERTY_NUMBER_OF_FRAMES:
      return host_.recordedFrames() > 0 ? TRUE : FALSE;
    default:
      return hasOwnProperty(property) ? TRUE : FALSE;
  }
}

OniStatus TumStream::getOwnProperty(int /*property*/, void* /*data*/, int* /*size*/,
                                    const OniVideoMode& /*mode*/) {
  return ONI_STATUS_NOT_IMPLEMENTED;
}

bool TumStream::hasOwnProperty(int /*property*/) const { return false; }

TUM_DEVICE_WRITES_OPENNI2_FRAMES
void TumStream::fillFrame(OniFrame* out, const Frame& frame, const VirtualCamera::Shot& shot,
                          const OniVideoMode& mode, const cv::Rect& rect, bool cropping,
                          bool mirroring) {
  const int bytes_per_pixel = bytesPerPixel(mode.pixelFormat);
  out->sensorType = type_;
  out->videoMode = mode;
  out->width = rect.width;
  out->height = rect.height;
  out->stride = rect.width * bytes_per_pixel;
  out->dataSize = out->stride * rect.height;
  out->croppingEnabled = cropping ? TRUE : FALSE;
  out->cropOriginX = rect.x;
  out->cropOriginY = rect.y;
  out->timestamp = timestampOf(shot);
  out->frameIndex = shot.frame_index;

  // A crop of the mirrored image is the mirror of the same-sized crop at the opposite side.
  const cv::Rect source =
      mirroring ? cv::Rect(mode.resolutionX - rect.x - rect.width, rect.y, rect.width, rect.height)
                : rect;
  cv::Mat target(rect.height, rect.width, bytes_per_pixel == 2 ? CV_16UC1 : CV_8UC3, out->data,
                 static_cast<std::size_t>(out->stride));
  writePixels(frame, source, mode, target);
  if (mirroring) cv::flip(target, target, 1);  // in place: cv::flip swaps column pairs
}

void TumStream::deliver(const Frame& frame, const VirtualCamera::Shot& shot) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!started_) return;
  if (frame.depth.cols != mode_.resolutionX || frame.depth.rows != mode_.resolutionY) {
    log_.warning("skipping frame " + std::to_string(shot.frame_index) + " (" + frame.origin +
                 "): images are " + std::to_string(frame.depth.cols) + "x" +
                 std::to_string(frame.depth.rows) + ", the device delivers " +
                 std::to_string(mode_.resolutionX) + "x" + std::to_string(mode_.resolutionY));
    return;
  }
  OniFrame* out = getServices().acquireFrame();
  if (out == nullptr) {
    log_.warning("OpenNI2 has no frame buffer free: frame " + std::to_string(shot.frame_index) +
                 " dropped");
    return;
  }
  fillFrame(out, frame, shot, mode_, deliveredRect(), cropping_.enabled != FALSE, mirroring_);
  raiseNewFrame(out);
  getServices().releaseFrame(out);
}

}  // namespace rgbdmap::openni2_tum
