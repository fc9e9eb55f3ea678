#include "color_stream.hpp"

#include <opencv2/imgproc.hpp>

namespace rgbdmap::openni2_tum {

ColorStream::ColorStream(const CameraIntrinsics& intrinsics, StreamHost& host, DriverLog& log)
    : TumStream(ONI_SENSOR_COLOR, videoModes(), intrinsics, host, log) {}

std::vector<OniVideoMode> ColorStream::videoModes() {
  return {{ONI_PIXEL_FORMAT_RGB888, kTumWidth, kTumHeight, kTumFps}};
}

TUM_DEVICE_WRITES_OPENNI2_FRAMES
void ColorStream::writePixels(const Frame& frame, const cv::Rect& source,
                              const OniVideoMode& /*mode*/, cv::Mat& target) {
  // TumSequence decodes to OpenCV's BGR; swapping back restores the PNG's RGB bytes. `target`
  // already has the size and type, so cvtColor writes into OpenNI2's buffer.
  cv::cvtColor(frame.color(source), target, cv::COLOR_BGR2RGB);
}

}  // namespace rgbdmap::openni2_tum
