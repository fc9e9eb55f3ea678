#pragma once

#include "tum_stream.hpp"

namespace rgbdmap::openni2_tum {

// Colour of the TUM pairs as RGB888, the bytes of the PNG unchanged.
class ColorStream : public TumStream {
 public:
  ColorStream(const CameraIntrinsics& intrinsics, StreamHost& host, DriverLog& log);

  static std::vector<OniVideoMode> videoModes();

 protected:
  void writePixels(const Frame& frame, const cv::Rect& source, const OniVideoMode& mode,
                   cv::Mat& target) override;
  std::uint64_t timestampOf(const VirtualCamera::Shot& shot) const override {
    return shot.color_timestamp_us;
  }
};

}  // namespace rgbdmap::openni2_tum
