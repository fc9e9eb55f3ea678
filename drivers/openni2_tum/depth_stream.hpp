#pragma once

#include "tum_stream.hpp"

namespace rgbdmap::openni2_tum {

// Depth of the TUM pairs. TUM stores 5000 units per metre (0.2 mm), exactly two 100 um
// steps, so ONI_PIXEL_FORMAT_DEPTH_100_UM (the default mode) is lossless up to 6.5535 m,
// the most it can hold (farther pixels become 0, no measurement). ONI_PIXEL_FORMAT_DEPTH_1_MM
// is offered for programs that want millimetres, rounded to the nearest one.
class DepthStream : public TumStream {
 public:
  DepthStream(const CameraIntrinsics& intrinsics, StreamHost& host, DriverLog& log);

  static std::vector<OniVideoMode> videoModes();

  // TUM depth is registered to the colour camera: a depth pixel is the same colour pixel.
  OniStatus convertDepthToColorCoordinates(StreamBase* color_stream, int depth_x, int depth_y,
                                           OniDepthPixel depth_z, int* color_x,
                                           int* color_y) override;

 protected:
  void writePixels(const Frame& frame, const cv::Rect& source, const OniVideoMode& mode,
                   cv::Mat& target) override;
  std::uint64_t timestampOf(const VirtualCamera::Shot& shot) const override {
    return shot.depth_timestamp_us;
  }
  OniStatus getOwnProperty(int property, void* data, int* size, const OniVideoMode& mode) override;
  bool hasOwnProperty(int property) const override;
};

}  // namespace rgbdmap::openni2_tum
