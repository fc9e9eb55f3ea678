#pragma once

#include <OpenNI.h>

#include <chrono>
#include <memory>
#include <string>

#include "disconnect_watch.hpp"
#include "rgbdmap/base/frame.hpp"
#include "runtime.hpp"

namespace rgbdmap::openni2 {

// A live camera that delivers nothing for this long counts as gone
// (ReadStatus::kTimeout).
constexpr std::chrono::milliseconds kReadTimeout{2000};

// What the user configured for the camera.
struct DeviceSettings {
  CameraIntrinsics camera;              // size to stream at, and the preset's intrinsics
  bool intrinsics_from_device = false;  // camera.intrinsics=device
};

// The OpenNI2 objects of one opened, configured and started device or recording: 640x480 (the
// configured size) at 30 fps, depth in 0.1 mm or 1 mm, colour RGB888, registration and frame
// sync where supported; recordings frame by frame without repeating.
class OpenDevice {
 public:
  // Opens `uri` ("" = the first device, a ".oni" path = a recording; `requested` is what the
  // user asked for, which names recordings). Throws InputError naming the device (with the USB
  // diagnosis for "" when `diagnose`), leaving nothing open.
  static std::unique_ptr<OpenDevice> open(std::shared_ptr<Runtime> runtime, const std::string& uri,
                                          const std::string& requested,
                                          const DeviceSettings& settings, bool diagnose);
  // Stops and closes; recordings are kept open until the process ends (see keepUntilExit).
  static void close(std::unique_ptr<OpenDevice> device);

  bool isFile() const { return is_file_; }
  const std::string& uri() const { return uri_; }      // a recording's path for files
  const std::string& label() const { return label_; }  // "openni2:URI" or "openni2:FILE.oni"
  const std::string& name() const { return name_; }    // vendor and model
  double metresPerUnit() const { return metres_per_unit_; }
  const CameraIntrinsics& intrinsics() const { return camera_; }
  int depthTotal() const { return depth_total_; }  // frames in a recording (0 = unknown)
  int colorTotal() const { return color_total_; }
  bool repeats() const { return repeats_; }  // a recording that starts over at its end
  // Set once OpenNI2 reports this device unplugged (null when it cannot tell).
  const DisconnectWatch* watch() const { return watch_.get(); }

  openni::Device& device() { return device_; }
  openni::VideoStream& depth() { return depth_; }
  openni::VideoStream& color() { return color_; }
  openni::VideoFrameRef& depthFrame() { return depth_frame_; }
  openni::VideoFrameRef& colorFrame() { return color_frame_; }

  OpenDevice(const OpenDevice&) = delete;
  OpenDevice& operator=(const OpenDevice&) = delete;

 private:
  OpenDevice(std::shared_ptr<Runtime> runtime, const std::string& requested,
             const DeviceSettings& settings);
  void configure();
  void chooseVideoModes();
  void setUpRegistrationAndSync();
  void setUpPlayback();
  void checkVideoModes();
  CameraIntrinsics intrinsicsFromDevice();
  void stopAndClose();

  // Declared first so that it is released last: OpenNI2 shuts down after
  // everything below.
  const std::shared_ptr<Runtime> runtime_;
  const std::string requested_;
  const DeviceSettings settings_;
  openni::Device device_;
  openni::VideoStream depth_;
  openni::VideoStream color_;
  openni::VideoFrameRef depth_frame_;
  openni::VideoFrameRef color_frame_;
  std::unique_ptr<DisconnectWatch> watch_;

  bool is_file_ = false;
  std::string uri_;
  std::string label_;
  std::string name_;
  double metres_per_unit_ = 0.001;
  CameraIntrinsics camera_;
  int depth_total_ = 0;
  int color_total_ = 0;
  bool repeats_ = false;
};

}  // namespace rgbdmap::openni2
