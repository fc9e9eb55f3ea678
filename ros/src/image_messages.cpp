#include "rgbdmap/ros/image_messages.hpp"

#include <sensor_msgs/image_encodings.h>

#include <opencv2/imgproc.hpp>

namespace rgbdmap {
namespace {

namespace enc = sensor_msgs::image_encodings;

// The message's pixels as a Mat without copying, after checking that they are all there.
bool view(const sensor_msgs::Image& msg, int type, cv::Mat& out, std::string& error) {
  const std::size_t row = static_cast<std::size_t>(msg.width) * CV_ELEM_SIZE(type);
  if (msg.width == 0 || msg.height == 0) {
    error = "empty image (" + std::to_string(msg.width) + "x" + std::to_string(msg.height) + ")";
    return false;
  }
  if (msg.step < row || msg.data.size() < static_cast<std::size_t>(msg.step) * msg.height) {
    error = "truncated image: " + std::to_string(msg.data.size()) + " bytes for " +
            std::to_string(msg.width) + "x" + std::to_string(msg.height) + " " + msg.encoding +
            " with step " + std::to_string(msg.step);
    return false;
  }
  // The data is read only; Mat has no const view, and nothing writes through this one.
  out = cv::Mat(static_cast<int>(msg.height), static_cast<int>(msg.width), type,
                const_cast<std::uint8_t*>(msg.data.data()), msg.step);
  return true;
}

bool bigEndianHost() {
  const std::uint16_t one = 1;
  return *reinterpret_cast<const std::uint8_t*>(&one) == 0;
}

}  // namespace

std::string colorEncodingProblem(const std::string& encoding) {
  if (encoding == enc::RGB8 || encoding == enc::BGR8) return "";
  return "colour encoding '" + encoding + "' is not supported (rgb8 or bgr8)";
}

std::string depthEncodingProblem(const std::string& encoding) {
  if (encoding == enc::TYPE_32FC1 || encoding == enc::TYPE_16UC1) return "";
  return "depth encoding '" + encoding + "' is not supported (32FC1 metres or 16UC1 millimetres)";
}

bool colorFromMessage(const sensor_msgs::Image& msg, cv::Mat& bgr, std::string& error) {
  error = colorEncodingProblem(msg.encoding);
  cv::Mat pixels;
  if (!error.empty() || !view(msg, CV_8UC3, pixels, error)) return false;
  if (msg.encoding == enc::RGB8)
    cv::cvtColor(pixels, bgr, cv::COLOR_RGB2BGR);
  else
    pixels.copyTo(bgr);
  return true;
}

bool depthFromMessage(const sensor_msgs::Image& msg, cv::Mat& metres, std::string& error) {
  error = depthEncodingProblem(msg.encoding);
  const bool millimetres = msg.encoding == enc::TYPE_16UC1;
  cv::Mat pixels;
  if (!error.empty() || !view(msg, millimetres ? CV_16UC1 : CV_32FC1, pixels, error)) return false;
  if ((msg.is_bigendian != 0) != bigEndianHost()) {
    error = "depth is stored with the other byte order (is_bigendian=" +
            std::to_string(msg.is_bigendian) + ")";
    return false;
  }
  if (millimetres) {
    pixels.convertTo(metres, CV_32F, 1e-3);
  } else {
    pixels.copyTo(metres);
    // ROS marks missing depth as NaN (REP 118); the mapper takes 0 for that.
    cv::patchNaNs(metres, 0.0);
  }
  return true;
}

CameraIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info) {
  CameraIntrinsics c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.fx = info.K[0];
  c.fy = info.K[4];
  c.cx = info.K[2];
  c.cy = info.K[5];
  if (info.distortion_model == "plumb_bob" || info.distortion_model == "rational_polynomial") {
    const auto d = [&](std::size_t i) { return i < info.D.size() ? info.D[i] : 0.0; };
    c.k1 = d(0);
    c.k2 = d(1);
    c.p1 = d(2);
    c.p2 = d(3);
    c.k3 = d(4);
  }
  return c;
}

bool intrinsicsFromCameraInfoWanted(const Config& config) {
  if (config.camera.intrinsics == "device") return true;
  if (config.preset != "default") return false;
  const CameraIntrinsics d;
  const CameraIntrinsics& c = config.camera;
  return c.width == d.width && c.height == d.height && c.fx == d.fx && c.fy == d.fy &&
         c.cx == d.cx && c.cy == d.cy && !c.hasDistortion();
}

double stampSeconds(std::uint32_t sec, std::uint32_t nsec) {
  return static_cast<double>(sec) + static_cast<double>(nsec) * 1e-9;
}

}  // namespace rgbdmap
