#include "rgbdmap/mapping/depth_filter.hpp"

#include <cmath>

#include "rgbdmap/base/vector_clones.hpp"

namespace rgbdmap {

DepthFilter::DepthFilter(const FilterOptions& o)
    : min_depth(o.min_depth),
      max_depth(o.max_depth),
      remove_flying_pixels(o.outliers == "fast"),
      edge_jump(o.edge_jump),
      min_neighbours(o.outliers == "fast" ? o.speck_min_neighbours : 0) {}

RGBDMAP_VECTOR_CLONES void DepthFilter::apply(const cv::Mat& input, cv::Mat& output,
                                              cv::Mat& scratch) const {
  CV_Assert(input.type() == CV_32FC1);
  const int rows = input.rows, cols = input.cols;
  const float lo = static_cast<float>(min_depth), hi = static_cast<float>(max_depth);
  // Decisions read the range-filtered input (a copy), so removing one pixel does not change
  // its neighbours' verdicts and the result does not depend on scan order. The copy has a
  // one-pixel border that repeats the edge: a border pixel counts itself for the missing side
  // (that only makes it easier to keep), and the loop below needs no special cases, so the
  // compiler vectorises it.
  scratch.create(rows + 2, cols + 2, CV_32FC1);
  for (int v = 0; v < rows; ++v) {
    const float* in = input.ptr<float>(v);
    float* range = scratch.ptr<float>(v + 1) + 1;
    for (int u = 0; u < cols; ++u) range[u] = (in[u] >= lo && in[u] <= hi) ? in[u] : 0.0f;
    range[-1] = range[0];  // also clears NaN
    range[cols] = range[cols - 1];
  }
  scratch.row(1).copyTo(scratch.row(0));
  scratch.row(rows).copyTo(scratch.row(rows + 1));
  output.create(rows, cols, CV_32FC1);

  const bool flying_test = remove_flying_pixels;
  const int needed = min_neighbours;
  const float jump = static_cast<float>(edge_jump);
  for (int v = 0; v < rows; ++v) {
    float* out = output.ptr<float>(v);
    const float* above = scratch.ptr<float>(v) + 1;
    const float* row = scratch.ptr<float>(v + 1) + 1;
    const float* below = scratch.ptr<float>(v + 2) + 1;
    for (int u = 0; u < cols; ++u) {
      const float z = row[u];
      const float tolerance = jump * z;
      // A missing neighbour is not a jump: holes are common on valid surfaces. A jump to a
      // 4-neighbour marks a flying pixel (depth mixed across a discontinuity).
      const auto jumps = [&](float n) { return (n != 0.0f) & (std::abs(n - z) > tolerance); };
      const bool flying = jumps(above[u]) | jumps(below[u]) | jumps(row[u - 1]) | jumps(row[u + 1]);
      // Specks: too few of the 8 neighbours at a similar depth.
      const auto similar = [&](float n) {
        return static_cast<int>((n != 0.0f) & (std::abs(n - z) <= tolerance));
      };
      const int neighbours = similar(above[u - 1]) + similar(above[u]) + similar(above[u + 1]) +
                             similar(row[u - 1]) + similar(row[u + 1]) + similar(below[u - 1]) +
                             similar(below[u]) + similar(below[u + 1]);
      const bool keep = !(flying_test & flying) & (neighbours >= needed);
      out[u] = keep ? z : 0.0f;
    }
  }
}

}  // namespace rgbdmap
