#pragma once

#include <Driver/OniDriverAPI.h>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "tum_stream.hpp"
#include "virtual_camera.hpp"

namespace rgbdmap::openni2_tum {

class DriverLog;

// One OpenNI2 device opened on a VirtualCamera. A playback thread (idle while no stream runs)
// decodes each associated pair once and hands it to every running stream at the recorded
// timing: the colour stamps of rgb.txt relative to the first pair played since the streams
// started. Depth and colour of a pair share a frame index, which is what OpenNI2's depth/colour
// frame sync matches on. Pairs whose images cannot be read are logged and skipped.
class TumDevice : public oni::driver::DeviceBase, private StreamHost {
 public:
  using UnplugHandler = std::function<void(const std::shared_ptr<VirtualCamera>&)>;

  // `on_unplugged` runs on the playback thread when disconnect_after is reached.
  TumDevice(std::shared_ptr<VirtualCamera> camera, DriverLog& log, UnplugHandler on_unplugged);
  TumDevice(const TumDevice&) = delete;
  TumDevice& operator=(const TumDevice&) = delete;
  ~TumDevice() override;  // stops the playback thread

  OniStatus getSensorInfoList(OniSensorInfo** sensors, int* count) override;
  oni::driver::StreamBase* createStream(OniSensorType type) override;
  void destroyStream(oni::driver::StreamBase* stream) override;
  OniStatus setProperty(int property, const void* data, int size) override;
  OniStatus getProperty(int property, void* data, int* size) override;
  OniBool isPropertySupported(int property) override;
  OniBool isImageRegistrationModeSupported(OniImageRegistrationMode mode) override;
  OniStatus invoke(int command, void* data, int size) override;
  OniBool isCommandSupported(int command) override;
  // Called by OpenNI2 when the host waits for a frame and none is there: at playback speed
  // <= 0 ("manual") the next pair comes then.
  OniStatus tryManualTrigger() override;

 private:
  bool streamStarted() override;
  void streamStopped() override;
  int recordedFrames() const override;
  // A folder without a simulated unplug plays like a recording (OpenNI2's Device::isFile()):
  // playback speed, repeat (the loop option), seek and a frame count; so a host knows where it
  // ends and can read it frame by frame. With disconnect_after it acts as a live camera.
  bool playsLikeRecording() const { return camera_->uri().disconnect_after == 0; }
  void play();
  void deliver(const Frame& frame, const VirtualCamera::Shot& shot);

  const std::shared_ptr<VirtualCamera> camera_;
  const std::uint64_t generation_;  // of the camera when opened: later ones are not ours
  DriverLog& log_;
  const UnplugHandler on_unplugged_;

  std::vector<OniVideoMode> depth_modes_;
  std::vector<OniVideoMode> color_modes_;
  OniSensorInfo sensors_[2];

  std::mutex streams_mutex_;  // held while delivering, so streams are not destroyed meanwhile
  std::vector<std::unique_ptr<TumStream>> streams_;

  std::mutex state_mutex_;
  std::condition_variable state_changed_;
  int running_streams_ = 0;
  int created_streams_ = 0;
  std::uint64_t runs_ = 0;  // times the first stream started: each restarts the time base
  bool closing_ = false;
  float speed_ = 1.0f;           // playback speed: a ratio of the recorded timing, <= 0 manual
  std::uint64_t reads_ = 0;      // the host asked for more (tryManualTrigger calls)
  std::uint64_t reads_due_ = 0;  // in manual mode, the next pair waits for reads_ to get here
                                 // (a poke after the last pair was handed out)
  std::thread player_;
};

}  // namespace rgbdmap::openni2_tum
