#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/kinect_noise.hpp"
#include "rgbdmap/mapping/point_batch.hpp"

namespace rgbdmap {

// Turns a depth image into world points. The viewing ray of every pixel is computed once
// (undistorted when the camera has lens distortion and `undistort` is set), so each frame costs
// a multiply per pixel.
class BackProjector {
 public:
  BackProjector(const CameraIntrinsics& camera, bool undistort);

  // Appends one point per valid depth pixel to `out`, in world coordinates, with its colour
  // (RGB) and a fusion weight 1 / sigma(z)^2 (normalised to 1 at 1 m).
  void project(const cv::Mat& depth, const cv::Mat& color_bgr, const Eigen::Isometry3d& pose,
               PointBatch& out) const;

  // Where pixels are much smaller than a voxel, neighbouring (smoothed) pixels add little: below
  // this depth only pixels with even row and column are projected. 0 projects every pixel.
  void setSubsampleBelowDepth(float depth) { subsample_below_depth_ = depth; }

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_, height_;
  float subsample_below_depth_ = 0.0f;
  std::vector<Eigen::Vector2f> rays_;  // (x/z, y/z) per pixel, row-major
};

}  // namespace rgbdmap
