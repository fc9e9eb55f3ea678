#pragma once

#include <Driver/OniDriverAPI.h>

#include <mutex>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "virtual_camera.hpp"

namespace rgbdmap::openni2_tum {

class DriverLog;

// Frames reach the host through libOpenNI2's own locks, which the test programs' ThreadSanitizer
// settings ignore (called_from_lib:libOpenNI2.so in src/sanitizer_defaults.cpp), so TSan cannot
// see that handover. The code that writes into OpenNI2's frame buffers is therefore left
// uninstrumented, as in drivers built without TSan (OniFile, PS1080); the rest of the plugin,
// its own threads and locks included, stays checked.
#define TUM_DEVICE_WRITES_OPENNI2_FRAMES __attribute__((no_sanitize_thread, noinline))

// TUM RGB-D was recorded with a Kinect v1: 640x480 at 30 Hz.
constexpr int kTumWidth = 640;
constexpr int kTumHeight = 480;
constexpr int kTumFps = 30;

// What a stream tells the device it belongs to.
class StreamHost {
 public:
  virtual ~StreamHost() = default;
  // Returns false when the device cannot deliver any more (it was unplugged).
  virtual bool streamStarted() = 0;
  virtual void streamStopped() = 0;
  // Pairs in the folder when the device plays like a recording, 0 when it acts as a live camera.
  virtual int recordedFrames() const = 0;
};

// The part of a depth or colour stream that does not depend on the pixels: video modes,
// cropping, mirroring, field of view, and handing frames to OpenNI2. Settings and delivery
// share one mutex, so a property change never meets a half-written frame and stop() returns
// only after a frame being delivered is out.
class TumStream : public oni::driver::StreamBase {
 public:
  TumStream(OniSensorType type, std::vector<OniVideoMode> modes, const CameraIntrinsics& intrinsics,
            StreamHost& host, DriverLog& log);

  OniStatus start() override;
  void stop() override;
  OniStatus setProperty(int property, const void* data, int size) override;
  OniStatus getProperty(int property, void* data, int* size) override;
  OniBool isPropertySupported(int property) override;
  int getRequiredFrameSize() override;

  // Called by the device's playback thread with a decoded pair; no-op while stopped.
  void deliver(const Frame& frame, const VirtualCamera::Shot& shot);

 protected:
  // Converts the part `source` of the decoded pair into `target`, which has that size and
  // the pixel format of `mode` and wraps OpenNI2's frame buffer.
  // Implementations are marked TUM_DEVICE_WRITES_OPENNI2_FRAMES.
  virtual void writePixels(const Frame& frame, const cv::Rect& source, const OniVideoMode& mode,
                           cv::Mat& target) = 0;
  virtual std::uint64_t timestampOf(const VirtualCamera::Shot& shot) const = 0;
  // Properties only one kind of stream has; called with the mutex held.
  virtual OniStatus getOwnProperty(int property, void* data, int* size, const OniVideoMode& mode);
  virtual bool hasOwnProperty(int property) const;

  const CameraIntrinsics intrinsics_;

 private:
  cv::Rect deliveredRect() const;  // in the delivered (possibly mirrored) image
  // Header and pixels of one frame for OpenNI2, from settings copied under the mutex.
  void fillFrame(OniFrame* out, const Frame& frame, const VirtualCamera::Shot& shot,
                 const OniVideoMode& mode, const cv::Rect& rect, bool cropping, bool mirroring);

  const OniSensorType type_;
  const std::vector<OniVideoMode> modes_;
  StreamHost& host_;
  DriverLog& log_;

  std::mutex mutex_;
  bool started_ = false;
  OniVideoMode mode_;
  OniCropping cropping_{};
  bool mirroring_ = false;
};

int bytesPerPixel(OniPixelFormat format);

}  // namespace rgbdmap::openni2_tum
