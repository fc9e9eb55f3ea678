#pragma once

#include <opencv2/core.hpp>

namespace rgbdmap {

// Cleans an organized depth image (CV_32FC1, metres, 0 = missing) in place, using pixel
// neighbourhoods instead of a k-d tree:
//  - range: depth outside [min_depth, max_depth] is dropped;
//  - flying pixels: a pixel whose depth differs from a 4-neighbour by more than
//    edge_jump * depth sits on a depth discontinuity, where the sensor mixes foreground and
//    background; it is dropped;
//  - specks: a pixel with fewer than min_neighbours of its 8 neighbours at a similar depth is
//    an isolated measurement; it is dropped.
struct DepthFilter {
  double min_depth = 0.3;
  double max_depth = 4.0;
  bool remove_flying_pixels = true;
  double edge_jump = 0.03;
  int min_neighbours = 4;

  // `scratch` is reused between calls to avoid allocating per frame.
  void apply(cv::Mat& depth, cv::Mat& scratch) const { apply(depth, depth, scratch); }
  // The same from `input` into `output` (which may be `input`), saving a copy.
  void apply(const cv::Mat& input, cv::Mat& output, cv::Mat& scratch) const;
};

}  // namespace rgbdmap
