#include "open_device.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "open_failure.hpp"
#include "rgbdmap/base/error.hpp"

namespace rgbdmap::openni2 {
namespace {

constexpr int kFps = 30;

const char* formatName(openni::PixelFormat format) {
  switch (format) {
    case openni::PIXEL_FORMAT_DEPTH_1_MM:
      return "DEPTH_1_MM";
    case openni::PIXEL_FORMAT_DEPTH_100_UM:
      return "DEPTH_100_UM";
    case openni::PIXEL_FORMAT_SHIFT_9_2:
      return "SHIFT_9_2";
    case openni::PIXEL_FORMAT_SHIFT_9_3:
      return "SHIFT_9_3";
    case openni::PIXEL_FORMAT_RGB888:
      return "RGB888";
    case openni::PIXEL_FORMAT_YUV422:
      return "YUV422";
    case openni::PIXEL_FORMAT_YUYV:
      return "YUYV";
    case openni::PIXEL_FORMAT_GRAY8:
      return "GRAY8";
    case openni::PIXEL_FORMAT_GRAY16:
      return "GRAY16";
    case openni::PIXEL_FORMAT_JPEG:
      return "JPEG";
  }
  return "unknown";
}

}  // namespace

OpenDevice::OpenDevice(std::shared_ptr<Runtime> runtime, const std::string& requested,
                       const DeviceSettings& settings)
    : runtime_(std::move(runtime)), requested_(requested), settings_(settings) {}

std::unique_ptr<OpenDevice> OpenDevice::open(std::shared_ptr<Runtime> runtime,
                                             const std::string& uri, const std::string& requested,
                                             const DeviceSettings& settings, bool diagnose) {
  const char* target = uri.empty() ? openni::ANY_DEVICE : uri.c_str();
  std::unique_ptr<OpenDevice> dev(new OpenDevice(std::move(runtime), requested, settings));
  if (dev->device_.open(target) != openni::STATUS_OK) throw InputError(openFailure(uri, diagnose));
  try {
    dev->configure();
  } catch (...) {
    close(std::move(dev));
    throw;
  }
  return dev;
}

void OpenDevice::close(std::unique_ptr<OpenDevice> dev) {
  if (!dev) return;
  dev->stopAndClose();
  if (dev->device_.isValid() && dev->device_.isFile()) keepUntilExit(std::move(dev));
}

void OpenDevice::stopAndClose() {
  if (watch_) {
    openni::OpenNI::removeDeviceDisconnectedListener(watch_.get());
    watch_.reset();
  }
  depth_frame_.release();
  color_frame_.release();
  if (depth_.isValid()) depth_.stop();
  if (color_.isValid()) color_.stop();
  if (device_.isValid() && device_.isFile()) return;  // kept open: see keepUntilExit
  if (depth_.isValid()) depth_.destroy();
  if (color_.isValid()) color_.destroy();
  if (device_.isValid()) device_.close();
}

void OpenDevice::configure() {
  const openni::DeviceInfo& info = device_.getDeviceInfo();
  is_file_ = device_.isFile();
  uri_ = info.getUri();
  label_ = "openni2:" + (is_file_ ? requested_ : uri_);
  name_ =
      is_file_ ? std::string("recording") : std::string(info.getVendor()) + " " + info.getName();
  if (!device_.hasSensor(openni::SENSOR_DEPTH)) throw InputError(label_ + ": has no depth stream");
  if (!device_.hasSensor(openni::SENSOR_COLOR)) throw InputError(label_ + ": has no colour stream");
  if (depth_.create(device_, openni::SENSOR_DEPTH) != openni::STATUS_OK)
    throw InputError(label_ + ": cannot create the depth stream (" + lastError() + ")");
  if (color_.create(device_, openni::SENSOR_COLOR) != openni::STATUS_OK)
    throw InputError(label_ + ": cannot create the colour stream (" + lastError() + ")");
  if (is_file_) {
    setUpPlayback();
  } else {
    chooseVideoModes();
  }
  setUpRegistrationAndSync();
  if (!is_file_) {
    watch_ = std::make_unique<DisconnectWatch>(uri_);
    if (openni::OpenNI::addDeviceDisconnectedListener(watch_.get()) != openni::STATUS_OK) {
      spdlog::warn(
          "{}: cannot watch for unplugging ({}); a vanished camera shows as a {} s timeout", label_,
          lastError(), kReadTimeout.count() / 1000.0);
      watch_.reset();
    }
  }
  if (depth_.start() != openni::STATUS_OK)
    throw InputError(label_ + ": cannot start the depth stream (" + lastError() + ")");
  if (color_.start() != openni::STATUS_OK)
    throw InputError(label_ + ": cannot start the colour stream (" + lastError() + ")");
  checkVideoModes();
  camera_ = intrinsicsFromDevice();
}

// 640x480 (the configured size) at 30 fps: depth in 0.1 mm when offered (finer
// than 1 mm at range), else 1 mm; colour as RGB888.
void OpenDevice::chooseVideoModes() {
  const CameraIntrinsics& wanted = settings_.camera;
  auto pick = [&](openni::VideoStream& stream,
                  std::initializer_list<openni::PixelFormat> formats) -> const openni::VideoMode* {
    const openni::Array<openni::VideoMode>& modes = stream.getSensorInfo().getSupportedVideoModes();
    for (const bool exact_fps : {true, false})
      for (const openni::PixelFormat format : formats)
        for (int i = 0; i < modes.getSize(); ++i)
          if (modes[i].getResolutionX() == wanted.width &&
              modes[i].getResolutionY() == wanted.height && modes[i].getPixelFormat() == format &&
              (!exact_fps || modes[i].getFps() == kFps))
            return &modes[i];
    return nullptr;
  };
  auto offered = [](openni::VideoStream& stream) {
    const openni::Array<openni::VideoMode>& modes = stream.getSensorInfo().getSupportedVideoModes();
    std::string list;
    for (int i = 0; i < modes.getSize(); ++i)
      list += (i ? ", " : "") + std::to_string(modes[i].getResolutionX()) + "x" +
              std::to_string(modes[i].getResolutionY()) + " " +
              formatName(modes[i].getPixelFormat()) + " " + std::to_string(modes[i].getFps()) +
              " fps";
    return list.empty() ? std::string("none") : list;
  };
  const std::string size = std::to_string(wanted.width) + "x" + std::to_string(wanted.height);
  const openni::VideoMode* depth_mode =
      pick(depth_, {openni::PIXEL_FORMAT_DEPTH_100_UM, openni::PIXEL_FORMAT_DEPTH_1_MM});
  if (!depth_mode)
    throw InputError(label_ + ": no " + size + " depth mode in DEPTH_100_UM or DEPTH_1_MM (it " +
                     "offers " + offered(depth_) + "); set camera.width/height to one of them");
  const openni::VideoMode* color_mode = pick(color_, {openni::PIXEL_FORMAT_RGB888});
  if (!color_mode)
    throw InputError(label_ + ": no " + size + " RGB888 colour mode (it offers " + offered(color_) +
                     "); set camera.width/height to one of them");
  if (depth_.setVideoMode(*depth_mode) != openni::STATUS_OK)
    throw InputError(label_ + ": cannot set depth " + size + " " +
                     formatName(depth_mode->getPixelFormat()) + " (" + lastError() + ")");
  if (color_.setVideoMode(*color_mode) != openni::STATUS_OK)
    throw InputError(label_ + ": cannot set colour " + size + " RGB888 (" + lastError() + ")");
  if (depth_mode->getFps() != kFps || color_mode->getFps() != kFps)
    spdlog::warn("{}: no {} fps mode; streaming depth at {} fps and colour at {} fps", label_, kFps,
                 depth_mode->getFps(), color_mode->getFps());
}

void OpenDevice::setUpRegistrationAndSync() {
  if (is_file_) {
    spdlog::info("{}: a recording plays as it was recorded (depth-to-colour registration {})",
                 label_,
                 device_.getImageRegistrationMode() == openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR
                     ? "on"
                     : "off or not recorded");
  } else if (!device_.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR)) {
    spdlog::warn(
        "{}: the device cannot register depth to colour: depth and colour pixels are misaligned by "
        "up to a few centimetres and colours bleed at edges",
        label_);
  } else if (device_.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) !=
             openni::STATUS_OK) {
    spdlog::warn(
        "{}: depth-to-colour registration failed to turn on ({}): depth and colour pixels are "
        "misaligned by up to a few centimetres",
        label_, lastError());
  } else {
    spdlog::info("{}: depth registered to colour by the device", label_);
  }
  if (device_.setDepthColorSyncEnabled(true) != openni::STATUS_OK)
    spdlog::warn(
        "{}: depth/colour frame sync is not supported ({}): each depth image is paired with the "
        "colour image that arrives next to it",
        label_, lastError());
}

// Recordings play frame by frame as they are read ("manual" speed -1): nothing
// is skipped however slowly the mapper reads; replay.rate timing is applied
// by the reader.
void OpenDevice::setUpPlayback() {
  openni::PlaybackControl* playback = device_.getPlaybackControl();
  if (!playback || !playback->isValid())
    throw InputError(label_ + ": OpenNI2 gives no playback control for this recording");
  if (playback->setSpeed(-1.0f) != openni::STATUS_OK)
    spdlog::warn("{}: cannot play frame by frame ({}); frames may be skipped", label_, lastError());
  // A .oni file plays once; other devices that play like recordings (a TUM folder through the
  // project's driver) repeat as their URI says (loop=1).
  const std::string suffix = ".oni";
  const bool oni_file =
      requested_.size() >= suffix.size() &&
      requested_.compare(requested_.size() - suffix.size(), suffix.size(), suffix) == 0;
  if (oni_file && playback->setRepeatEnabled(false) != openni::STATUS_OK)
    spdlog::warn(
        "{}: cannot turn off repeating ({}); the recording ends after {} s without a frame", label_,
        lastError(), kReadTimeout.count() / 1000.0);
  repeats_ = !oni_file && playback->getRepeatEnabled();
  if (repeats_) spdlog::info("{}: plays in a loop until stopped", label_);
  depth_total_ = std::max(playback->getNumberOfFrames(depth_), 0);
  color_total_ = std::max(playback->getNumberOfFrames(color_), 0);
  if (depth_total_ == 0 || color_total_ == 0)
    throw InputError(label_ + ": the recording has " + std::to_string(depth_total_) +
                     " depth and " + std::to_string(color_total_) +
                     " colour frames; it needs both");
}

void OpenDevice::checkVideoModes() {
  const openni::VideoMode depth = depth_.getVideoMode();
  const openni::VideoMode color = color_.getVideoMode();
  if (depth.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM)
    metres_per_unit_ = 0.001;
  else if (depth.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM)
    metres_per_unit_ = 0.0001;
  else
    throw InputError(label_ + ": depth comes as " + formatName(depth.getPixelFormat()) +
                     "; rgbdmap reads DEPTH_1_MM and DEPTH_100_UM");
  if (color.getPixelFormat() != openni::PIXEL_FORMAT_RGB888)
    throw InputError(label_ + ": colour comes as " + formatName(color.getPixelFormat()) +
                     "; rgbdmap reads RGB888");
  if (depth.getResolutionX() != color.getResolutionX() ||
      depth.getResolutionY() != color.getResolutionY())
    throw InputError(label_ + ": depth is " + std::to_string(depth.getResolutionX()) + "x" +
                     std::to_string(depth.getResolutionY()) + " but colour is " +
                     std::to_string(color.getResolutionX()) + "x" +
                     std::to_string(color.getResolutionY()) + "; they must match");
  spdlog::debug("{}: depth {}x{} {}, colour RGB888", label_, depth.getResolutionX(),
                depth.getResolutionY(), formatName(depth.getPixelFormat()));
}

// The preset's intrinsics, or (camera.intrinsics=device) a pinhole from the
// field of view the device reports: f = size / (2 tan(fov / 2)), centred.
// Colour's view is preferred since depth is registered to it; the depth
// stream's serves when colour reports none.
CameraIntrinsics OpenDevice::intrinsicsFromDevice() {
  const CameraIntrinsics& configured = settings_.camera;
  const openni::VideoMode mode = depth_.getVideoMode();
  const int width = mode.getResolutionX();
  const int height = mode.getResolutionY();
  if (!settings_.intrinsics_from_device) {
    if (width != configured.width || height != configured.height)
      throw InputError(
          label_ + ": delivers " + std::to_string(width) + "x" + std::to_string(height) +
          " but the camera is configured as " + std::to_string(configured.width) + "x" +
          std::to_string(configured.height) +
          "; set camera.width/height/fx/fy/cx/cy to match, or --set camera.intrinsics=device");
    return configured;
  }
  auto valid = [](float fov) { return std::isfinite(fov) && fov > 0.01f && fov < 3.1f; };
  float hfov = color_.getHorizontalFieldOfView();
  float vfov = color_.getVerticalFieldOfView();
  const char* from = "colour";
  if (!valid(hfov) || !valid(vfov)) {
    hfov = depth_.getHorizontalFieldOfView();
    vfov = depth_.getVerticalFieldOfView();
    from = "depth";
  }
  if (!valid(hfov) || !valid(vfov))
    throw InputError(
        label_ +
        ": reports no field of view for camera.intrinsics=device; use camera.intrinsics=preset");
  CameraIntrinsics camera;
  camera.width = width;
  camera.height = height;
  camera.fx = width / (2.0 * std::tan(hfov / 2.0));
  camera.fy = height / (2.0 * std::tan(vfov / 2.0));
  camera.cx = (width - 1) / 2.0;
  camera.cy = (height - 1) / 2.0;
  spdlog::info(
      "{}: intrinsics from the {} stream's field of view ({:.4f} x {:.4f} rad): fx {:.1f} fy "
      "{:.1f} cx {:.1f} cy {:.1f}",
      label_, from, hfov, vfov, camera.fx, camera.fy, camera.cx, camera.cy);
  return camera;
}

}  // namespace rgbdmap::openni2
