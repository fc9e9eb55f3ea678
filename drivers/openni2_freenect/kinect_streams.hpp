#pragma once

#include <Driver/OniDriverAPI.h>

#include <cstdint>
#include <mutex>
#include <vector>

#include "rgbdmap/drivers/kinect_v1_model.hpp"

namespace rgbdmap::openni2_freenect {

// Frames reach the host through libOpenNI2's own locks, which ThreadSanitizer is told to ignore
// (src/sanitizer_defaults.cpp); the code writing into OpenNI2's frame buffers stays
// uninstrumented, as in the drivers OpenNI2 ships (see drivers/openni2_tum/tum_stream.hpp).
#define KINECT_WRITES_OPENNI2_FRAMES __attribute__((no_sanitize_thread, noinline))

constexpr int kFps = 30;

// What a stream asks of its device.
class StreamHost {
 public:
  virtual ~StreamHost() = default;
  virtual bool streamStarted(OniSensorType type) = 0;  // false when the Kinect is gone
  virtual void streamStopped(OniSensorType type) = 0;
  virtual bool registered() const = 0;  // depth registered to colour
};

// A Kinect v1 stream at 640x480, 30 fps: video mode, mirroring and field of view, and handing
// frames to OpenNI2 (stamped by the host's monotonic clock in microseconds, since libfreenect's
// device clock is not in known units).
class KinectStream : public oni::driver::StreamBase {
 public:
  KinectStream(OniSensorType type, std::vector<OniVideoMode> modes, StreamHost& host);

  OniStatus start() override;
  void stop() override;
  OniStatus setProperty(int property, const void* data, int size) override;
  OniStatus getProperty(int property, void* data, int* size) override;
  OniBool isPropertySupported(int property) override;

  static std::vector<OniVideoMode> depthModes();
  static std::vector<OniVideoMode> colorModes();

 protected:
  // Fills an OpenNI2 frame with `write(pixels, mode, mirroring)` and raises it; no-op stopped.
  template <typename Write>
  void deliver(Write&& write);

 private:
  const OniSensorType type_;
  const std::vector<OniVideoMode> modes_;

 protected:
  StreamHost& host_;
  std::mutex mutex_;  // settings and delivery
  bool started_ = false;
  OniVideoMode mode_;
  bool mirroring_ = false;
  int frame_index_ = 0;
};

// Depth from raw 11-bit disparity: metres by the Kinect's factory model, registered to colour
// when the device's registration is on, in DEPTH_1_MM or DEPTH_100_UM.
class KinectDepthStream : public KinectStream {
 public:
  KinectDepthStream(StreamHost& host, const KinectV1Model& model);
  void deliverRaw(const std::uint16_t* raw);  // a kWidth x kHeight IR-view frame

 private:
  const KinectV1Model& model_;
  std::vector<std::uint16_t> registered_;
};

// Colour as RGB888, as libfreenect gives it.
class KinectColorStream : public KinectStream {
 public:
  explicit KinectColorStream(StreamHost& host);
  void deliverRgb(const std::uint8_t* rgb);
};

}  // namespace rgbdmap::openni2_freenect
