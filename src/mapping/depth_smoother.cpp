#include "rgbdmap/mapping/depth_smoother.hpp"

#include <opencv2/imgproc.hpp>

namespace rgbdmap {

void DepthSmoother::apply(cv::Mat& depth, cv::Mat& inverse, cv::Mat& valid, cv::Mat& sum,
                          cv::Mat& count, cv::Mat& low, cv::Mat& high) const {
  CV_Assert(depth.type() == CV_32FC1);
  if (radius <= 0) return;
  const cv::Size window(2 * radius + 1, 2 * radius + 1);
  const float window_pixels = static_cast<float>(window.area());
  const int cols = depth.cols;

  // inverse = 1/z where measured, 0 elsewhere; valid = 1 where measured. The loops below have no
  // division and no conditional load, so the compiler vectorises them.
  cv::divide(1.0, depth, inverse);
  valid.create(depth.size(), CV_32FC1);
  // Missing pixels must not win the min/max test: they are +inf for the minimum, 0 for the max.
  low.create(depth.size(), CV_32FC1);
  for (int v = 0; v < depth.rows; ++v) {
    const float* z = depth.ptr<float>(v);
    float* inv = inverse.ptr<float>(v);
    float* ok = valid.ptr<float>(v);
    float* lo = low.ptr<float>(v);
    for (int u = 0; u < cols; ++u) {
      const float d = z[u];
      const bool measured = d > 0.0f;
      inv[u] = measured ? inv[u] : 0.0f;  // 1/0 is inf
      ok[u] = measured ? 1.0f : 0.0f;
      lo[u] = measured ? d : std::numeric_limits<float>::max();
    }
  }
  // Box sums are O(1) per pixel whatever the radius; erode/dilate give the window's depth range.
  cv::boxFilter(inverse, sum, CV_32F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(valid, count, CV_32F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, window);
  cv::erode(low, low, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
            cv::Scalar(std::numeric_limits<float>::max()));
  cv::dilate(depth, high, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));

  // The window's mean inverse depth, inverted: count / sum (used only where count > 0).
  cv::divide(count, sum, sum);
  const float min_count = static_cast<float>(min_valid_fraction) * window_pixels;
  const float range = static_cast<float>(max_relative_range);
  const float fallback = drop_unsmoothed ? 0.0f : 1.0f;
  for (int v = 0; v < depth.rows; ++v) {
    float* z = depth.ptr<float>(v);
    const float* mean = sum.ptr<float>(v);
    const float* n = count.ptr<float>(v);
    const float* lo = low.ptr<float>(v);
    const float* hi = high.ptr<float>(v);
    for (int u = 0; u < cols; ++u) {
      // Too few pixels, or the window straddles an edge: keep the measurement. (Every value is
      // read unconditionally, so the compiler vectorises the loop.)
      const float measured = z[u], smoothed = mean[u];
      const bool enough = n[u] >= min_count, flat = hi[u] - lo[u] <= range * measured;
      z[u] = ((measured > 0.0f) & enough & flat) ? smoothed : fallback * measured;
    }
  }
}

}  // namespace rgbdmap
