#pragma once

#include <opencv2/core.hpp>

namespace rgbdmap {

// Reduces per-pixel depth noise before fusion by averaging inverse depth over a square window.
// Inverse depth is linear in the pixel coordinates on a plane, so the mean of a full symmetric
// window is exact on planar surfaces (no bias), while the noise shrinks by the square root of
// the number of pixels averaged. Windows that straddle a depth discontinuity (their depth range
// exceeds max_relative_range * depth) or miss too many pixels keep the measured value, so edges
// are not smeared between foreground and background.
struct DepthSmoother {
  int radius = 2;                    // window (2r+1)^2; 0 disables smoothing
  double max_relative_range = 0.03;  // depth spread in the window allowed, relative to depth
  double min_valid_fraction = 0.75;  // share of window pixels that must have depth
  // Pixels that cannot be smoothed (edges, sparse windows) keep their measurement by default.
  // Dropping them instead keeps the raw noise (25x the variance) out of a fused map, where
  // its tails would become isolated points 1-2 cm off the surfaces; other views fill in.
  bool drop_unsmoothed = false;

  // Smooths `depth` (CV_32FC1, metres, 0 = missing) in place. The scratch images are reused.
  void apply(cv::Mat& depth, cv::Mat& inverse, cv::Mat& valid, cv::Mat& sum, cv::Mat& count,
             cv::Mat& low, cv::Mat& high) const;
};

}  // namespace rgbdmap
