#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace rgbdmap {

// Pinhole intrinsics with the Brown-Conrady distortion TUM and OpenCV use.
struct CameraIntrinsics {
  int width = 640;
  int height = 480;
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;

  bool hasDistortion() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0 || k3 != 0; }
  cv::Matx33d cameraMatrix() const { return {fx, 0, cx, 0, fy, cy, 0, 0, 1}; }
  cv::Vec<double, 5> distortion() const { return {k1, k2, p1, p2, k3}; }
};

// One registered depth + colour capture. Frames live in a FramePool and are reused, so the
// images are written in place (same size every time) instead of being reallocated.
struct Frame {
  std::uint64_t index = 0;  // position in the stream, counting from 0
  double timestamp = 0.0;   // seconds (colour image stamp)
  cv::Mat depth;            // CV_32FC1, metres, 0 = no measurement
  cv::Mat color;            // CV_8UC3, BGR (OpenCV order)
  bool has_pose = false;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera-to-world
  // The tracking keyframe the pose was estimated against (-1: none, e.g. ground truth): a loop
  // closure that moves that keyframe moves this pose with it (see PoseCorrections).
  std::int64_t anchor = -1;
  // The camera's up direction in its own frame, from an accelerometer (TUM's accelerometer.txt);
  // unset when the source has none or the camera was being shaken.
  bool has_up = false;
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  std::string origin;        // where it came from, for messages (a file name or device)
  double captured_at = 0.0;  // steady-clock seconds when the capture thread queued it
};

// `from` into `to`: same-size images are copied in place and an origin that fits the reserved
// capacity is too (no allocation: frames are reused).
inline void copyFrame(const Frame& from, Frame& to) {
  to.index = from.index;
  to.timestamp = from.timestamp;
  from.depth.copyTo(to.depth);
  from.color.copyTo(to.color);
  to.has_pose = from.has_pose;
  to.pose = from.pose;
  to.anchor = from.anchor;
  to.has_up = from.has_up;
  to.up = from.up;
  to.origin.assign(from.origin);
  to.captured_at = from.captured_at;
}

}  // namespace rgbdmap
