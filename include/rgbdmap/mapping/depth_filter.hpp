#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "rgbdmap/base/option_keys.hpp"

namespace rgbdmap {

// How depth images are cleaned before fusion (config section "filter"): DepthFilter's range and
// outlier tests, the smoothing window, PCL's statistical filter and lens undistortion (see
// KeyframeIntegrator). The depth range also bounds tracking and loop closure.
struct FilterOptions {
  double min_depth = 0.3;  // m
  // m. 5, not 4: a Kinect measures to 4.5-5 m, and the far walls it sees hold fast turns
  // (fr1/rpy's excerpts 3.72 -> 3.08 cm on average) and fill a floor's far rooms (recall 0.894
  // -> 0.924 on the 30 x 20 m floor); docs/benchmarks.md.
  double max_depth = 5.0;
  // Undo lens distortion when the camera has it (key camera.undistort, which sets
  // TrackingOptions::undistort too: one lens).
  bool undistort = true;
  std::string outliers = "fast";  // fast | statistical | none
  double edge_jump = 0.03;        // relative depth jump that marks a flying pixel
  int speck_min_neighbours = 4;   // of 8, with similar depth
  bool subsample = true;          // every 2nd pixel where 2 pixels < half a voxel
  int smooth_radius = 2;          // inverse-depth averaging window, 0 = off
  // A smoothing window is one surface when its depth spread is within smooth_range * depth plus
  // smooth_noise_sigmas * sigma(depth); fusion drops a pixel whose window is not. The noise term
  // is what lets far surfaces in: 25 samples of a Kinect's noise alone spread about 4 sigma, more
  // than 3% of the depth beyond 3 m, so floors and upper walls seen from afar were never fused
  // (the 30 x 20 m floor's recall 0.924 -> 0.972, precision 0.9961 -> 0.9960; docs/benchmarks.md).
  double smooth_range = 0.03;
  double smooth_noise_sigmas = 4.0;
  int sor_mean_k = 50;
  double sor_stddev = 1.0;
};

Keys filterKeys(FilterOptions& o);

// Cleans an organized depth image (CV_32FC1, metres, 0 = missing) in place, using pixel
// neighbourhoods instead of a k-d tree:
//  - range: depth outside [min_depth, max_depth] is dropped;
//  - flying pixels: a pixel whose depth differs from a 4-neighbour by more than
//    edge_jump * depth sits on a depth discontinuity, where the sensor mixes foreground and
//    background; it is dropped;
//  - specks: a pixel with fewer than min_neighbours of its 8 neighbours at a similar depth is
//    an isolated measurement; it is dropped.
struct DepthFilter {
  DepthFilter() : DepthFilter(FilterOptions{}) {}
  // filter.outliers other than "fast" turns the flying-pixel and speck tests off.
  explicit DepthFilter(const FilterOptions& o);

  double min_depth;
  double max_depth;
  bool remove_flying_pixels;
  double edge_jump;
  int min_neighbours;

  // `scratch` is reused between calls to avoid allocating per frame.
  void apply(cv::Mat& depth, cv::Mat& scratch) const { apply(depth, depth, scratch); }
  // The same from `input` into `output` (which may be `input`), saving a copy.
  void apply(const cv::Mat& input, cv::Mat& output, cv::Mat& scratch) const;
};

}  // namespace rgbdmap
