#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/capture/camera_options.hpp"

namespace rgbdmap {

// Depth from a camera of its own (raw Kinect streams, 7-Scenes) moved into the colour camera:
// each depth pixel back-projected with the depth camera's intrinsics, moved by the extrinsic and
// projected through the colour camera's lens, the nearest surface kept where several land on one
// pixel. Everything after it (tracking, fusion, places) sees depth registered to colour, as from
// TUM's sequences and OpenNI2's registered mode.
class DepthRegistration {
 public:
  explicit DepthRegistration(const CameraOptions& camera);

  // `depth`: CV_32FC1 metres, 0 = none, in the depth camera; replaced by the registered image.
  void apply(cv::Mat& depth);

  // The depth camera's pose in the colour camera's frame.
  const Eigen::Isometry3d& colorFromDepth() const { return color_from_depth_; }

 private:
  CameraIntrinsics color_;
  CameraIntrinsics depth_;
  Eigen::Isometry3d color_from_depth_;
  std::vector<Eigen::Vector2f> rays_;  // per depth pixel: (x/z, y/z) in the depth camera
};

}  // namespace rgbdmap
