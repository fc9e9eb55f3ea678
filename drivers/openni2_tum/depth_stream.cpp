#include "depth_stream.hpp"

#include <cmath>
#include <cstdint>

#include "rgbdmap/drivers/oni_property.hpp"

namespace rgbdmap::openni2_tum {
namespace {

double unitsPerMetre(OniPixelFormat format) {
  return format == ONI_PIXEL_FORMAT_DEPTH_100_UM ? 10000.0 : 1000.0;
}

}  // namespace

DepthStream::DepthStream(const CameraIntrinsics& intrinsics, StreamHost& host, DriverLog& log)
    : TumStream(ONI_SENSOR_DEPTH, videoModes(), intrinsics, host, log) {}

std::vector<OniVideoMode> DepthStream::videoModes() {
  return {{ONI_PIXEL_FORMAT_DEPTH_100_UM, kTumWidth, kTumHeight, kTumFps},
          {ONI_PIXEL_FORMAT_DEPTH_1_MM, kTumWidth, kTumHeight, kTumFps}};
}

TUM_DEVICE_WRITES_OPENNI2_FRAMES
void DepthStream::writePixels(const Frame& frame, const cv::Rect& source, const OniVideoMode& mode,
                              cv::Mat& target) {
  // Frames carry metres as float (TumSequence's 16-bit value / 5000): value * 10000 is within
  // 0.02 of the even integer 2 * value, and value * 1000 within 0.002 of value / 5, whose
  // fraction is never .5; rounding therefore gives exactly 2 * value and round(value / 5).
  const double scale = unitsPerMetre(mode.pixelFormat);
  for (int y = 0; y < source.height; ++y) {
    const float* in = frame.depth.ptr<float>(source.y + y) + source.x;
    std::uint16_t* out = target.ptr<std::uint16_t>(y);
    for (int x = 0; x < source.width; ++x) {
      const double units = static_cast<double>(in[x]) * scale;
      // Not positive (or NaN): no measurement; beyond the format's range: cannot be shown.
      out[x] = units > 0 && units < 65535.5 ? static_cast<std::uint16_t>(std::lround(units)) : 0;
    }
  }
}

OniStatus DepthStream::getOwnProperty(int property, void* data, int* size,
                                      const OniVideoMode& mode) {
  switch (property) {
    case ONI_STREAM_PROPERTY_MIN_VALUE:
      return writeProperty(data, size, 0);
    case ONI_STREAM_PROPERTY_MAX_VALUE:
      // The largest TUM value (65535 / 5000 m) in this format, capped by 16 bits.
      return writeProperty(data, size,
                           mode.pixelFormat == ONI_PIXEL_FORMAT_DEPTH_100_UM ? 65535 : 13107);
    default:
      return ONI_STATUS_NOT_IMPLEMENTED;
  }
}

bool DepthStream::hasOwnProperty(int property) const {
  return property == ONI_STREAM_PROPERTY_MIN_VALUE || property == ONI_STREAM_PROPERTY_MAX_VALUE;
}

OniStatus DepthStream::convertDepthToColorCoordinates(StreamBase* /*color_stream*/, int depth_x,
                                                      int depth_y, OniDepthPixel /*depth_z*/,
                                                      int* color_x, int* color_y) {
  if (color_x == nullptr || color_y == nullptr) return ONI_STATUS_BAD_PARAMETER;
  *color_x = depth_x;
  *color_y = depth_y;
  return ONI_STATUS_OK;
}

}  // namespace rgbdmap::openni2_tum
