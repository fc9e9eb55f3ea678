#include "rgbdmap/mapping/depth_smoother.hpp"

#include <algorithm>
#include <limits>

#include "rgbdmap/base/kinect_noise.hpp"
#include "rgbdmap/base/vector_clones.hpp"

namespace rgbdmap {

// Four quantities per window: the sum of inverse depths, the pixels with depth, and the lowest
// and highest depth. Each is taken per pixel first, then down the window's 2r+1 rows into one row
// of columns, then across 2r+1 columns. Outside the image counts as missing. Each loop reads one
// array and writes one, along a row and without a branch, so the compiler vectorises every one
// (with several arrays per loop it cannot rule out enough overlaps, and does not).
RGBDMAP_VECTOR_CLONES void DepthSmoother::apply(cv::Mat& depth, Buffers& buffers) const {
  CV_Assert(depth.type() == CV_32FC1);
  if (radius <= 0) return;
  const int rows = depth.rows, cols = depth.cols, r = radius;
  constexpr float kNoLow = std::numeric_limits<float>::max();
  const auto add = [](float a, float b) { return a + b; };
  const auto lower = [](float a, float b) { return b < a ? b : a; };
  const auto higher = [](float a, float b) { return b > a ? b : a; };

  depth.copyTo(buffers.high_of);  // also the measurement, as the image is overwritten
  const auto per_pixel = [&](cv::Mat& image, auto value) {
    image.create(rows, cols, CV_32FC1);
    for (int v = 0; v < rows; ++v) {
      const float* z = buffers.high_of.ptr<float>(v);
      float* out = image.ptr<float>(v);
      for (int u = 0; u < cols; ++u) out[u] = value(z[u]);
    }
  };
  per_pixel(buffers.inverse_of, [](float z) { return z > 0.0f ? 1.0f / z : 0.0f; });
  per_pixel(buffers.count_of, [](float z) { return z > 0.0f ? 1.0f : 0.0f; });
  per_pixel(buffers.low_of, [](float z) { return z > 0.0f ? z : kNoLow; });

  // Window columns are padded with r "missing" entries on either side, so a window never needs
  // a bounds check.
  const std::size_t padded = static_cast<std::size_t>(cols + 2 * r);
  buffers.sum.assign(padded, 0.0f);
  buffers.count.assign(padded, 0.0f);
  buffers.low.assign(padded, kNoLow);
  buffers.high.assign(padded, 0.0f);
  for (std::vector<float>* window :
       {&buffers.window_sum, &buffers.window_count, &buffers.window_low, &buffers.window_high})
    window->resize(static_cast<std::size_t>(cols));

  const float min_count =
      static_cast<float>(min_valid_fraction) * static_cast<float>((2 * r + 1) * (2 * r + 1));
  const float range = static_cast<float>(max_relative_range);
  const float noise = static_cast<float>(noise_sigmas);
  const float fallback = drop_unsmoothed ? 0.0f : 1.0f;
  for (int v = 0; v < rows; ++v) {
    const int first = std::max(0, v - r), last = std::min(rows - 1, v + r);
    const auto down = [&](const cv::Mat& image, std::vector<float>& columns, auto combine) {
      float* column = columns.data() + r;
      std::copy(image.ptr<float>(first), image.ptr<float>(first) + cols, column);
      for (int row = first + 1; row <= last; ++row) {
        const float* in = image.ptr<float>(row);
        for (int u = 0; u < cols; ++u) column[u] = combine(column[u], in[u]);
      }
    };
    down(buffers.inverse_of, buffers.sum, add);
    down(buffers.count_of, buffers.count, add);
    down(buffers.low_of, buffers.low, lower);
    down(buffers.high_of, buffers.high, higher);

    const auto across = [&](const std::vector<float>& columns, std::vector<float>& windows,
                            auto combine) {
      float* window = windows.data();
      std::copy(columns.data(), columns.data() + cols, window);
      for (int k = 1; k <= 2 * r; ++k) {
        const float* shifted = columns.data() + k;
        for (int u = 0; u < cols; ++u) window[u] = combine(window[u], shifted[u]);
      }
    };
    across(buffers.sum, buffers.window_sum, add);
    across(buffers.count, buffers.window_count, add);
    across(buffers.low, buffers.window_low, lower);
    across(buffers.high, buffers.window_high, higher);

    const float* sum = buffers.window_sum.data();
    const float* count = buffers.window_count.data();
    const float* low = buffers.window_low.data();
    const float* high = buffers.window_high.data();
    const float* measured_row = buffers.high_of.ptr<float>(v);
    float* out = depth.ptr<float>(v);
    for (int u = 0; u < cols; ++u) {
      // Too few pixels, or the window straddles an edge: keep the measurement. The mean of the
      // inverse depths, inverted, is count / sum.
      const float measured = measured_row[u], smoothed = count[u] / sum[u];
      const bool enough = count[u] >= min_count;
      const bool flat = high[u] - low[u] <= range * measured + noise * kinectDepthSigma(measured);
      out[u] = ((measured > 0.0f) & enough & flat) ? smoothed : fallback * measured;
    }
  }
}

}  // namespace rgbdmap
