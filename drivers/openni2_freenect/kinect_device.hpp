#pragma once

#include <Driver/OniDriverAPI.h>
#include <libfreenect.h>

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "kinect_streams.hpp"
#include "rgbdmap/drivers/kinect_accelerometer.hpp"
#include "rgbdmap/drivers/kinect_v1_model.hpp"

namespace rgbdmap::openni2_freenect {

// One Kinect v1 opened through libfreenect (a real one, or a dump replayed by fakenect): raw
// 11-bit depth and RGB at 640x480, 30 fps, converted and registered here (fakenect offers
// nothing else, so one path serves both). An event thread runs libfreenect while a stream runs;
// when libfreenect reports the device gone (unplugged, or the end of a fakenect dump) the
// streams stop delivering and `on_unplugged` tells OpenNI2. The accelerometer (in the tilt
// motor's USB device, opened when it can be) is read after every depth frame and offered as the
// kKinectAccelerationProperty.
class KinectDevice : public oni::driver::DeviceBase, private StreamHost {
 public:
  // Throws std::runtime_error when libfreenect cannot open device `index`.
  KinectDevice(int index, std::function<void()> on_unplugged);
  KinectDevice(const KinectDevice&) = delete;
  KinectDevice& operator=(const KinectDevice&) = delete;
  ~KinectDevice() override;

  OniStatus getSensorInfoList(OniSensorInfo** sensors, int* count) override;
  oni::driver::StreamBase* createStream(OniSensorType type) override;
  void destroyStream(oni::driver::StreamBase* stream) override;
  OniStatus setProperty(int property, const void* data, int size) override;
  OniStatus getProperty(int property, void* data, int* size) override;
  OniBool isPropertySupported(int property) override;
  OniBool isImageRegistrationModeSupported(OniImageRegistrationMode mode) override;

 private:
  bool streamStarted(OniSensorType type) override;
  void streamStopped(OniSensorType type) override;
  bool registered() const override { return registered_.load(); }
  void runEvents();
  void readAccelerometer();
  void stopEvents();
  static void onDepth(freenect_device* device, void* data, std::uint32_t timestamp);
  static void onVideo(freenect_device* device, void* data, std::uint32_t timestamp);

  const std::function<void()> on_unplugged_;
  const KinectV1Model model_;
  std::vector<OniVideoMode> depth_modes_;
  std::vector<OniVideoMode> color_modes_;
  OniSensorInfo sensors_[2];
  std::vector<std::uint16_t> depth_buffer_;  // libfreenect writes into these
  std::vector<std::uint8_t> video_buffer_;

  freenect_context* context_ = nullptr;
  freenect_device* device_ = nullptr;
  std::atomic<bool> registered_{false};
  std::atomic<bool> gone_{false};
  bool has_motor_ = false;                  // the accelerometer can be read
  std::atomic<bool> depth_arrived_{false};  // since the accelerometer was last read
  std::mutex acceleration_mutex_;
  bool has_acceleration_ = false;
  KinectAcceleration acceleration_;

  std::mutex mutex_;  // streams, what runs, the event thread
  std::condition_variable changed_;
  std::unique_ptr<KinectDepthStream> depth_;
  std::unique_ptr<KinectColorStream> color_;
  int created_ = 0;
  bool depth_running_ = false;
  bool video_running_ = false;
  bool stopping_events_ = false;
  std::thread events_;
};

}  // namespace rgbdmap::openni2_freenect
