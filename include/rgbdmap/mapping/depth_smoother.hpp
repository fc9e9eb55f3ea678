#pragma once

#include <opencv2/core.hpp>
#include <vector>

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
  // Allowed besides max_relative_range * depth: this many sigmas of the sensor's depth noise
  // (KinectNoise), so that the noise of far pixels alone does not mark their windows as edges.
  double noise_sigmas = 0.0;
  // Pixels that cannot be smoothed (edges, sparse windows) keep their measurement by default.
  // Dropping them instead keeps the raw noise (25x the variance) out of a fused map, where
  // its tails would become isolated points 1-2 cm off the surfaces; other views fill in.
  bool drop_unsmoothed = false;

  // What apply() works in, kept between calls so that a frame allocates nothing.
  struct Buffers {
    cv::Mat high_of;  // per pixel: its depth as measured (the image is overwritten row by row)
    cv::Mat inverse_of, count_of, low_of;      // 1 / depth or 0, 1 or 0, depth or +max
    std::vector<float> sum, count, low, high;  // a row's window columns, padded
    std::vector<float> window_sum, window_count, window_low, window_high;  // its windows
  };

  // Smooths `depth` (CV_32FC1, metres, 0 = missing) in place.
  void apply(cv::Mat& depth, Buffers& buffers) const;
};

}  // namespace rgbdmap
