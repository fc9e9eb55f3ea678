#include "rgbdmap/drivers/openni2_source.hpp"

#include <OpenNI.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/drivers/usb_cameras.hpp"

namespace rgbdmap {
namespace {

using Clock = std::chrono::steady_clock;

// A live camera that delivers nothing for this long counts as gone
// (ReadStatus::kTimeout).
constexpr std::chrono::milliseconds kReadTimeout{2000};
// How long one reconnect() keeps trying to reopen the device.
constexpr std::chrono::milliseconds kReconnectWindow{1000};
constexpr std::chrono::milliseconds kReconnectRetry{200};
constexpr int kFps = 30;

// Initialises OpenNI2 for its first user and shuts it down after its last one.
// Every object that holds OpenNI2 state keeps a reference, so none outlives
// OpenNI::shutdown() (a known crash). Nothing static holds a reference:
// shutting down from an exit handler, after the drivers' own statics are gone,
// makes Debian's PS1080 driver free memory twice.
class OpenNI2Runtime {
 public:
  static std::shared_ptr<OpenNI2Runtime> acquire() {
    std::lock_guard<std::mutex> lock(mutex());
    if (users() == 0 && openni::OpenNI::initialize() != openni::STATUS_OK)
      throw InputError(std::string("OpenNI2 cannot start: ") + openni::OpenNI::getExtendedError());
    ++users();
    return std::shared_ptr<OpenNI2Runtime>(new OpenNI2Runtime, [](OpenNI2Runtime* runtime) {
      delete runtime;
      std::lock_guard<std::mutex> lock(mutex());
      if (--users() == 0) openni::OpenNI::shutdown();
    });
  }
  OpenNI2Runtime(const OpenNI2Runtime&) = delete;
  OpenNI2Runtime& operator=(const OpenNI2Runtime&) = delete;

 private:
  OpenNI2Runtime() = default;
  static std::mutex& mutex() {
    static std::mutex instance;
    return instance;
  }
  static int& users() {
    static int count = 0;
    return count;
  }
};

// OpenNI2's extended error without its tabs and trailing newlines.
std::string openni2Error() {
  std::string text = openni::OpenNI::getExtendedError();
  std::replace(text.begin(), text.end(), '\t', ' ');
  std::replace(text.begin(), text.end(), '\n', ' ');
  const auto first = text.find_first_not_of(' ');
  const auto last = text.find_last_not_of(' ');
  return first == std::string::npos ? "no details" : text.substr(first, last - first + 1);
}

bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

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

// The reason `rgbdmap --source openni2` found nothing, from what the USB bus
// shows.
std::string noCameraMessage(const std::string& openni_error) {
  std::string message =
      "--source openni2: no camera found: OpenNI2 opened no device (" + openni_error + ")";
  const UsbScan scan = scanUsbCameras();
  if (!scan.bus_readable)
    return message + "; the USB bus could not be read either (" + scan.bus_error + ")";
  if (!scan.anyCamera()) {
    message +=
        "; the USB bus shows no Kinect v1 (045e:02ae), PrimeSense/ASUS Xtion (1d27:06xx) or Orbbec "
        "(2bc5:*) camera";
    message += scan.devices_seen == 0
                   ? std::string(" and no USB device at all (in a container, pass /dev/bus/usb in)")
                   : " among its " + std::to_string(scan.devices_seen) + " devices";
    if (!scan.cameras.empty())
      message +=
          "; only the motor/audio parts of a Kinect v1 are there: its camera needs the Kinect's "
          "own power supply plugged in";
    return message +
           ". Plug a camera in, or replay a recording: --source openni2:FILE.oni or --source "
           "tum:DIR (`rgbdmap devices` lists cameras and access)";
  }
  message += "; on the USB bus:";
  for (const UsbCamera& camera : scan.cameras) {
    message += "\n  " + camera.describe();
    if (!camera.problem.empty()) message += "; " + camera.problem;
    if (!camera.advice.empty()) message += "; " + camera.advice;
  }
  return message;
}

// Reports when OpenNI2 announces that the opened device went away (unplugged),
// so a read can stop waiting at once instead of after the full timeout.
class DisconnectWatch : public openni::OpenNI::DeviceDisconnectedListener {
 public:
  explicit DisconnectWatch(std::string uri) : uri_(std::move(uri)) {}
  void onDeviceDisconnected(const openni::DeviceInfo* info) override {
    if (info && uri_ == info->getUri()) disconnected_.store(true);
  }
  bool disconnected() const { return disconnected_.load(); }

 private:
  const std::string uri_;
  std::atomic<bool> disconnected_{false};
};

// The OpenNI2 objects of one open device. The runtime reference comes first, so OpenNI2 shuts
// down only after the device is closed.
struct OpenDevice {
  std::shared_ptr<OpenNI2Runtime> runtime;
  openni::Device device;
  openni::VideoStream depth;
  openni::VideoStream color;
  openni::VideoFrameRef depth_frame;
  openni::VideoFrameRef color_frame;
};

// Recordings that have been played, left open until the process ends. Debian's OniFile driver
// crashes in its player thread about one time in ten when a recording is closed (or OpenNI2 shut
// down after one); never closing them, and so never shutting OpenNI2 down, avoids it. The list
// is never freed (reachable from here, so leak checkers do not count it).
void keepOpenUntilExit(std::unique_ptr<OpenDevice> device) {
  static std::mutex mutex;
  static auto* kept = new std::vector<std::unique_ptr<OpenDevice>>();
  std::lock_guard<std::mutex> lock(mutex);
  kept->push_back(std::move(device));
}

class OpenNI2Source : public FrameSource {
 public:
  OpenNI2Source(const std::string& uri_or_file, const Config& config)
      : runtime_(OpenNI2Runtime::acquire()),
        requested_(uri_or_file),
        config_camera_(config.camera),
        intrinsics_from_device_(config.camera_intrinsics == "device"),
        rate_(config.rate) {
    open(requested_, true);
    reopen_uri_ = uri_;
  }
  ~OpenNI2Source() override { close(); }

  ReadStatus read(Frame& frame) override;
  CameraIntrinsics intrinsics() const override { return camera_; }
  bool isLive() const override { return !is_file_; }
  bool providesPoses() const override { return false; }
  std::string describe() const override;
  std::uint64_t skipped() const override { return skipped_; }
  bool canReconnect() const override { return !is_file_; }
  bool reconnect() override;

 private:
  const std::string& label() const { return label_; }
  // Opens and starts the device; throws InputError (with the USB diagnosis for
  // "" when `diagnose`). Leaves everything closed when it throws.
  void open(const std::string& uri, bool diagnose);
  void configure();
  void chooseVideoModes();
  void setUpRegistrationAndSync();
  void setUpPlayback();
  void checkVideoModes();
  CameraIntrinsics intrinsicsFromDevice();
  void close();
  std::string openFailure(const std::string& uri, bool diagnose) const;
  void pace(double stamp);

  // Declared first so that it is released last: OpenNI2 shuts down after
  // everything below.
  std::shared_ptr<OpenNI2Runtime> runtime_;
  const std::string requested_;
  const CameraIntrinsics config_camera_;
  const bool intrinsics_from_device_;
  const double rate_;

  std::string uri_;         // of the open device (a recording's path for files)
  std::string reopen_uri_;  // the device reconnect() looks for
  std::string name_;        // vendor and model
  std::string label_;       // "openni2:URI" or "openni2:FILE.oni", for messages and
                            // Frame::origin
  bool is_file_ = false;
  bool open_ = false;
  bool ever_opened_ = false;
  std::unique_ptr<OpenDevice> dev_;  // null while closed
  std::unique_ptr<DisconnectWatch> watch_;

  double metres_per_unit_ = 0.001;
  CameraIntrinsics camera_;
  int depth_total_ = 0;  // frames in a recording (0 = unknown)
  int color_total_ = 0;
  int depth_read_ = 0;
  int color_read_ = 0;
  bool ended_ = false;
  std::uint64_t skipped_ = 0;
  bool paced_ = false;
  double first_stamp_ = 0;
  Clock::time_point first_time_;
};

std::string OpenNI2Source::openFailure(const std::string& uri, bool diagnose) const {
  const std::string error = openni2Error();
  if (endsWith(uri, ".oni")) {
    struct stat st {};
    if (::stat(uri.c_str(), &st) != 0) return "openni2:" + uri + ": no such recording file";
    return "openni2:" + uri + ": OpenNI2 cannot play this file as a recording (" +
           (error == "no details" ? std::string("corrupt or truncated?") : error) + ")";
  }
  if (uri.empty()) {
    return diagnose ? noCameraMessage(error) : "openni2: no camera found (" + error + ")";
  }
  std::string message = "openni2:" + uri + ": OpenNI2 cannot open this device (" + error + ")";
  if (!diagnose) return message;
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  message += "; devices OpenNI2 lists: ";
  if (devices.getSize() == 0) message += "none";
  for (int i = 0; i < devices.getSize(); ++i)
    message += std::string(i ? ", " : "") + devices[i].getUri();
  return message;
}

void OpenNI2Source::open(const std::string& uri, bool diagnose) {
  const char* target = uri.empty() ? openni::ANY_DEVICE : uri.c_str();
  dev_ = std::make_unique<OpenDevice>();
  dev_->runtime = runtime_;
  if (dev_->device.open(target) != openni::STATUS_OK) {
    dev_.reset();
    throw InputError(openFailure(uri, diagnose));
  }
  try {
    configure();
  } catch (...) {
    close();
    throw;
  }
  open_ = true;
  ever_opened_ = true;
}

void OpenNI2Source::configure() {
  const openni::DeviceInfo& info = dev_->device.getDeviceInfo();
  is_file_ = dev_->device.isFile();
  uri_ = info.getUri();
  label_ = "openni2:" + (is_file_ ? requested_ : uri_);
  name_ =
      is_file_ ? std::string("recording") : std::string(info.getVendor()) + " " + info.getName();
  if (!dev_->device.hasSensor(openni::SENSOR_DEPTH))
    throw InputError(label() + ": has no depth stream");
  if (!dev_->device.hasSensor(openni::SENSOR_COLOR))
    throw InputError(label() + ": has no colour stream");
  if (dev_->depth.create(dev_->device, openni::SENSOR_DEPTH) != openni::STATUS_OK)
    throw InputError(label() + ": cannot create the depth stream (" + openni2Error() + ")");
  if (dev_->color.create(dev_->device, openni::SENSOR_COLOR) != openni::STATUS_OK)
    throw InputError(label() + ": cannot create the colour stream (" + openni2Error() + ")");
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
          "{}: cannot watch for unplugging ({}); a vanished camera shows as a {} s timeout",
          label(), openni2Error(), kReadTimeout.count() / 1000.0);
      watch_.reset();
    }
  }
  if (dev_->depth.start() != openni::STATUS_OK)
    throw InputError(label() + ": cannot start the depth stream (" + openni2Error() + ")");
  if (dev_->color.start() != openni::STATUS_OK)
    throw InputError(label() + ": cannot start the colour stream (" + openni2Error() + ")");
  checkVideoModes();
  const CameraIntrinsics camera = intrinsicsFromDevice();
  if (ever_opened_ && (camera.width != camera_.width || camera.height != camera_.height))
    throw InputError(label() + ": came back as " + std::to_string(camera.width) + "x" +
                     std::to_string(camera.height) + " instead of " +
                     std::to_string(camera_.width) + "x" + std::to_string(camera_.height));
  if (!ever_opened_) camera_ = camera;
  depth_read_ = color_read_ = 0;
  ended_ = false;
  paced_ = false;
}

// 640x480 (the configured size) at 30 fps: depth in 0.1 mm when offered (finer
// than 1 mm at range), else 1 mm; colour as RGB888.
void OpenNI2Source::chooseVideoModes() {
  auto pick = [&](openni::VideoStream& stream,
                  std::initializer_list<openni::PixelFormat> formats) -> const openni::VideoMode* {
    const openni::Array<openni::VideoMode>& modes = stream.getSensorInfo().getSupportedVideoModes();
    for (const bool exact_fps : {true, false})
      for (const openni::PixelFormat format : formats)
        for (int i = 0; i < modes.getSize(); ++i)
          if (modes[i].getResolutionX() == config_camera_.width &&
              modes[i].getResolutionY() == config_camera_.height &&
              modes[i].getPixelFormat() == format && (!exact_fps || modes[i].getFps() == kFps))
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
  const std::string size =
      std::to_string(config_camera_.width) + "x" + std::to_string(config_camera_.height);
  const openni::VideoMode* depth_mode =
      pick(dev_->depth, {openni::PIXEL_FORMAT_DEPTH_100_UM, openni::PIXEL_FORMAT_DEPTH_1_MM});
  if (!depth_mode)
    throw InputError(label() + ": no " + size + " depth mode in DEPTH_100_UM or DEPTH_1_MM (it " +
                     "offers " + offered(dev_->depth) +
                     "); set camera.width/height to one of them");
  const openni::VideoMode* color_mode = pick(dev_->color, {openni::PIXEL_FORMAT_RGB888});
  if (!color_mode)
    throw InputError(label() + ": no " + size + " RGB888 colour mode (it offers " +
                     offered(dev_->color) + "); set camera.width/height to one of them");
  if (dev_->depth.setVideoMode(*depth_mode) != openni::STATUS_OK)
    throw InputError(label() + ": cannot set depth " + size + " " +
                     formatName(depth_mode->getPixelFormat()) + " (" + openni2Error() + ")");
  if (dev_->color.setVideoMode(*color_mode) != openni::STATUS_OK)
    throw InputError(label() + ": cannot set colour " + size + " RGB888 (" + openni2Error() + ")");
  if (depth_mode->getFps() != kFps || color_mode->getFps() != kFps)
    spdlog::warn("{}: no {} fps mode; streaming depth at {} fps and colour at {} fps", label(),
                 kFps, depth_mode->getFps(), color_mode->getFps());
}

void OpenNI2Source::setUpRegistrationAndSync() {
  if (is_file_) {
    spdlog::info(
        "{}: a recording plays as it was recorded (depth-to-colour registration {})", label(),
        dev_->device.getImageRegistrationMode() == openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR
            ? "on"
            : "off or not recorded");
  } else if (!dev_->device.isImageRegistrationModeSupported(
                 openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR)) {
    spdlog::warn(
        "{}: the device cannot register depth to colour: depth and colour pixels are misaligned by "
        "up to a few centimetres and colours bleed at edges",
        label());
  } else if (dev_->device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) !=
             openni::STATUS_OK) {
    spdlog::warn(
        "{}: depth-to-colour registration failed to turn on ({}): depth and colour pixels are "
        "misaligned by up to a few centimetres",
        label(), openni2Error());
  } else {
    spdlog::info("{}: depth registered to colour by the device", label());
  }
  if (dev_->device.setDepthColorSyncEnabled(true) != openni::STATUS_OK)
    spdlog::warn(
        "{}: depth/colour frame sync is not supported ({}): each depth image is paired with the "
        "colour image that arrives next to it",
        label(), openni2Error());
}

// Recordings play frame by frame as they are read ("manual" speed -1): nothing
// is skipped however slowly the mapper reads; replay.rate timing is applied
// here, in read().
void OpenNI2Source::setUpPlayback() {
  openni::PlaybackControl* playback = dev_->device.getPlaybackControl();
  if (!playback || !playback->isValid())
    throw InputError(label() + ": OpenNI2 gives no playback control for this recording");
  if (playback->setSpeed(-1.0f) != openni::STATUS_OK)
    spdlog::warn("{}: cannot play frame by frame ({}); frames may be skipped", label(),
                 openni2Error());
  if (playback->setRepeatEnabled(false) != openni::STATUS_OK)
    spdlog::warn(
        "{}: cannot turn off repeating ({}); the recording ends after {} s without a frame",
        label(), openni2Error(), kReadTimeout.count() / 1000.0);
  depth_total_ = std::max(playback->getNumberOfFrames(dev_->depth), 0);
  color_total_ = std::max(playback->getNumberOfFrames(dev_->color), 0);
  if (depth_total_ == 0 || color_total_ == 0)
    throw InputError(label() + ": the recording has " + std::to_string(depth_total_) +
                     " depth and " + std::to_string(color_total_) +
                     " colour frames; it needs both");
}

void OpenNI2Source::checkVideoModes() {
  const openni::VideoMode depth = dev_->depth.getVideoMode();
  const openni::VideoMode color = dev_->color.getVideoMode();
  if (depth.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM)
    metres_per_unit_ = 0.001;
  else if (depth.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM)
    metres_per_unit_ = 0.0001;
  else
    throw InputError(label() + ": depth comes as " + formatName(depth.getPixelFormat()) +
                     "; rgbdmap reads DEPTH_1_MM and DEPTH_100_UM");
  if (color.getPixelFormat() != openni::PIXEL_FORMAT_RGB888)
    throw InputError(label() + ": colour comes as " + formatName(color.getPixelFormat()) +
                     "; rgbdmap reads RGB888");
  if (depth.getResolutionX() != color.getResolutionX() ||
      depth.getResolutionY() != color.getResolutionY())
    throw InputError(label() + ": depth is " + std::to_string(depth.getResolutionX()) + "x" +
                     std::to_string(depth.getResolutionY()) + " but colour is " +
                     std::to_string(color.getResolutionX()) + "x" +
                     std::to_string(color.getResolutionY()) + "; they must match");
  spdlog::debug("{}: depth {}x{} {}, colour RGB888", label(), depth.getResolutionX(),
                depth.getResolutionY(), formatName(depth.getPixelFormat()));
}

// The preset's intrinsics, or (camera.intrinsics=device) a pinhole from the
// field of view the device reports: f = size / (2 tan(fov / 2)), centred.
// Colour's view is preferred since depth is registered to it; the depth
// stream's serves when colour reports none.
CameraIntrinsics OpenNI2Source::intrinsicsFromDevice() {
  const openni::VideoMode mode = dev_->depth.getVideoMode();
  const int width = mode.getResolutionX();
  const int height = mode.getResolutionY();
  if (!intrinsics_from_device_) {
    if (width != config_camera_.width || height != config_camera_.height)
      throw InputError(
          label() + ": delivers " + std::to_string(width) + "x" + std::to_string(height) +
          " but the camera is configured as " + std::to_string(config_camera_.width) + "x" +
          std::to_string(config_camera_.height) +
          "; set camera.width/height/fx/fy/cx/cy to match, or --set camera.intrinsics=device");
    return config_camera_;
  }
  auto valid = [](float fov) { return std::isfinite(fov) && fov > 0.01f && fov < 3.1f; };
  float hfov = dev_->color.getHorizontalFieldOfView();
  float vfov = dev_->color.getVerticalFieldOfView();
  const char* from = "colour";
  if (!valid(hfov) || !valid(vfov)) {
    hfov = dev_->depth.getHorizontalFieldOfView();
    vfov = dev_->depth.getVerticalFieldOfView();
    from = "depth";
  }
  if (!valid(hfov) || !valid(vfov))
    throw InputError(
        label() +
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
      label(), from, hfov, vfov, camera.fx, camera.fy, camera.cx, camera.cy);
  return camera;
}

void OpenNI2Source::close() {
  if (watch_) {
    openni::OpenNI::removeDeviceDisconnectedListener(watch_.get());
    watch_.reset();
  }
  open_ = false;
  if (!dev_) return;
  dev_->depth_frame.release();
  dev_->color_frame.release();
  if (dev_->depth.isValid()) dev_->depth.stop();
  if (dev_->color.isValid()) dev_->color.stop();
  if (dev_->device.isValid() && dev_->device.isFile()) {
    keepOpenUntilExit(std::move(dev_));
    return;
  }
  if (dev_->depth.isValid()) dev_->depth.destroy();
  if (dev_->color.isValid()) dev_->color.destroy();
  if (dev_->device.isValid()) dev_->device.close();
  dev_.reset();
}

std::string OpenNI2Source::describe() const {
  const std::string size = std::to_string(camera_.width) + "x" + std::to_string(camera_.height);
  if (is_file_)
    return label() + " (recording, " + std::to_string(depth_total_) + " depth + " +
           std::to_string(color_total_) + " colour frames, " + size + ")";
  return label() + " (" + name_ + ", " + size + ")";
}

ReadStatus OpenNI2Source::read(Frame& frame) {
  if (ended_) return ReadStatus::kEnd;
  if (!open_)
    return ReadStatus::kTimeout;  // still unplugged: reconnect() has not
                                  // succeeded
  openni::VideoStream* streams[] = {&dev_->depth, &dev_->color};
  bool have_depth = false;
  bool have_color = false;
  bool wrong_size = false;
  const Clock::time_point deadline = Clock::now() + kReadTimeout;
  while (!have_depth || !have_color) {
    if (watch_ && watch_->disconnected()) {
      spdlog::warn("{}: OpenNI2 reports the device disconnected", label());
      return ReadStatus::kTimeout;
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) {
      if (!is_file_) return ReadStatus::kTimeout;
      // The frame counts promised more than the file holds (a truncated
      // recording).
      spdlog::warn(
          "{}: no frame for {} s after {} depth and {} colour frames of {} + {}; taking it as the "
          "end of the recording",
          label(), kReadTimeout.count() / 1000.0, depth_read_, color_read_, depth_total_,
          color_total_);
      ended_ = true;
      return ReadStatus::kEnd;
    }
    // Short waits, so an unplug event is noticed promptly.
    int ready = -1;
    const int wait_ms = static_cast<int>(std::min<long>(left.count(), 100));
    const openni::Status status = openni::OpenNI::waitForAnyStream(streams, 2, &ready, wait_ms);
    if (status == openni::STATUS_TIME_OUT) continue;
    if (status != openni::STATUS_OK) {
      spdlog::debug("{}: waiting for frames: {}", label(), openni2Error());
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    openni::VideoStream& stream = ready == 0 ? dev_->depth : dev_->color;
    openni::VideoFrameRef& ref = ready == 0 ? dev_->depth_frame : dev_->color_frame;
    if (stream.readFrame(&ref) != openni::STATUS_OK || !ref.isValid()) continue;
    const int width = ref.getWidth();
    const int height = ref.getHeight();
    if (width != camera_.width || height != camera_.height) wrong_size = true;
    if (ready == 0) {
      ++depth_read_;
      have_depth = true;
      if (wrong_size) continue;
      // In place: the Frame's images keep their buffers (same size and type
      // every time).
      const cv::Mat units(height, width, CV_16UC1, const_cast<void*>(ref.getData()),
                          static_cast<std::size_t>(ref.getStrideInBytes()));
      units.convertTo(frame.depth, CV_32F, metres_per_unit_);
    } else {
      ++color_read_;
      have_color = true;
      if (wrong_size) continue;
      const cv::Mat rgb(height, width, CV_8UC3, const_cast<void*>(ref.getData()),
                        static_cast<std::size_t>(ref.getStrideInBytes()));
      cv::cvtColor(rgb, frame.color, cv::COLOR_RGB2BGR);
      frame.timestamp = static_cast<double>(ref.getTimestamp()) * 1e-6;  // device clock, µs
    }
  }
  if (is_file_ && (depth_read_ >= depth_total_ || color_read_ >= color_total_)) ended_ = true;
  if (wrong_size) {
    spdlog::warn("{}: skipping a frame of {}x{} (depth) / {}x{} (colour); the camera is {}x{}",
                 label(), dev_->depth_frame.getWidth(), dev_->depth_frame.getHeight(),
                 dev_->color_frame.getWidth(), dev_->color_frame.getHeight(), camera_.width,
                 camera_.height);
    ++skipped_;
    return ReadStatus::kSkipped;
  }
  frame.has_pose = false;
  frame.origin = label();
  if (is_file_ && rate_ > 0) pace(frame.timestamp);
  return ReadStatus::kFrame;
}

// Releases recorded frames at their recorded spacing divided by replay.rate.
void OpenNI2Source::pace(double stamp) {
  if (!paced_) {
    paced_ = true;
    first_stamp_ = stamp;
    first_time_ = Clock::now();
    return;
  }
  const double offset = std::max(0.0, (stamp - first_stamp_) / rate_);
  std::this_thread::sleep_until(first_time_ + std::chrono::duration_cast<Clock::duration>(
                                                  std::chrono::duration<double>(offset)));
}

bool OpenNI2Source::reconnect() {
  close();
  // A replugged camera may get a new USB address and URI; when the user asked
  // for "the first camera", any camera will do.
  std::vector<std::string> candidates{reopen_uri_};
  if (requested_.empty()) candidates.push_back("");
  const Clock::time_point give_up = Clock::now() + kReconnectWindow;
  std::string last_error;
  for (;;) {
    for (const std::string& uri : candidates) {
      try {
        open(uri, false);
        spdlog::info("{}: reopened", label());
        return true;
      } catch (const InputError& e) {
        last_error = e.what();
      }
    }
    if (Clock::now() + kReconnectRetry >= give_up) break;
    std::this_thread::sleep_for(kReconnectRetry);
  }
  spdlog::debug("openni2:{}: not back yet: {}", reopen_uri_, last_error);
  return false;
}

}  // namespace

std::unique_ptr<FrameSource> openOpenNI2Source(const std::string& uri_or_file,
                                               const Config& config) {
  return std::make_unique<OpenNI2Source>(uri_or_file, config);
}

std::vector<std::string> listOpenNI2Devices() {
  const std::shared_ptr<OpenNI2Runtime> runtime = OpenNI2Runtime::acquire();
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  std::vector<std::string> list;
  for (int i = 0; i < devices.getSize(); ++i) {
    char ids[16];
    std::snprintf(ids, sizeof ids, "%04x:%04x", devices[i].getUsbVendorId(),
                  devices[i].getUsbProductId());
    list.push_back(std::string(devices[i].getUri()) + " (" + devices[i].getVendor() + " " +
                   devices[i].getName() + ", USB " + ids + ")");
  }
  return list;
}

}  // namespace rgbdmap
