#include "rgbdmap/depth_filter.hpp"

#include <cmath>

namespace rgbdmap {

void DepthFilter::apply(cv::Mat& depth, cv::Mat& scratch) const {
  CV_Assert(depth.type() == CV_32FC1);
  const float lo = static_cast<float>(min_depth), hi = static_cast<float>(max_depth);
  for (int v = 0; v < depth.rows; ++v) {
    float* row = depth.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u)
      if (!(row[u] >= lo && row[u] <= hi)) row[u] = 0.0f;  // also clears NaN
  }
  if (!remove_flying_pixels && min_neighbours <= 0) return;

  // Decisions read the range-filtered input (a copy), so removing one pixel does not change
  // its neighbours' verdicts and the result does not depend on scan order.
  depth.copyTo(scratch);
  const float jump = static_cast<float>(edge_jump);
  const int rows = depth.rows, cols = depth.cols;
  for (int v = 0; v < rows; ++v) {
    float* out = depth.ptr<float>(v);
    const float* above = scratch.ptr<float>(v > 0 ? v - 1 : v);
    const float* row = scratch.ptr<float>(v);
    const float* below = scratch.ptr<float>(v + 1 < rows ? v + 1 : v);
    for (int u = 0; u < cols; ++u) {
      const float z = row[u];
      if (z == 0.0f) continue;
      const float tolerance = jump * z;
      const int ul = u > 0 ? u - 1 : u, ur = u + 1 < cols ? u + 1 : u;
      if (remove_flying_pixels) {
        // A missing neighbour is not a jump: holes are common on valid surfaces.
        const float n4[4] = {above[u], below[u], row[ul], row[ur]};
        bool flying = false;
        for (float n : n4) flying |= (n != 0.0f && std::abs(n - z) > tolerance);
        if (flying) {
          out[u] = 0.0f;
          continue;
        }
      }
      if (min_neighbours > 0) {
        const float n8[8] = {above[ul], above[u], above[ur], row[ul],
                             row[ur],   below[ul], below[u], below[ur]};
        int similar = 0;
        for (float n : n8) similar += (n != 0.0f && std::abs(n - z) <= tolerance) ? 1 : 0;
        // Border pixels count themselves for the missing side; that only makes them easier to keep.
        if (similar < min_neighbours) out[u] = 0.0f;
      }
    }
  }
}

}  // namespace rgbdmap
