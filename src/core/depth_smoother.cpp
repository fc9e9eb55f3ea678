#include "rgbdmap/depth_smoother.hpp"

#include <opencv2/imgproc.hpp>

namespace rgbdmap {

void DepthSmoother::apply(cv::Mat& depth, cv::Mat& inverse, cv::Mat& valid, cv::Mat& sum,
                          cv::Mat& count, cv::Mat& low, cv::Mat& high) const {
  CV_Assert(depth.type() == CV_32FC1);
  if (radius <= 0) return;
  const cv::Size window(2 * radius + 1, 2 * radius + 1);
  const float window_pixels = static_cast<float>(window.area());

  // inverse = 1/z where measured, 0 elsewhere; valid = 1 where measured.
  inverse.create(depth.size(), CV_32FC1);
  valid.create(depth.size(), CV_32FC1);
  // Missing pixels must not win the min/max test: they are +inf for the minimum, 0 for the max.
  low.create(depth.size(), CV_32FC1);
  for (int v = 0; v < depth.rows; ++v) {
    const float* z = depth.ptr<float>(v);
    float* inv = inverse.ptr<float>(v);
    float* ok = valid.ptr<float>(v);
    float* lo = low.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) {
      const bool measured = z[u] > 0.0f;
      inv[u] = measured ? 1.0f / z[u] : 0.0f;
      ok[u] = measured ? 1.0f : 0.0f;
      lo[u] = measured ? z[u] : std::numeric_limits<float>::max();
    }
  }
  // Box sums are O(1) per pixel whatever the radius; erode/dilate give the window's depth range.
  cv::boxFilter(inverse, sum, CV_32F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(valid, count, CV_32F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, window);
  cv::erode(low, low, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
            cv::Scalar(std::numeric_limits<float>::max()));
  cv::dilate(depth, high, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));

  const float min_count = static_cast<float>(min_valid_fraction) * window_pixels;
  const float range = static_cast<float>(max_relative_range);
  for (int v = 0; v < depth.rows; ++v) {
    float* z = depth.ptr<float>(v);
    const float* s = sum.ptr<float>(v);
    const float* n = count.ptr<float>(v);
    const float* lo = low.ptr<float>(v);
    const float* hi = high.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) {
      if (z[u] <= 0.0f || n[u] < min_count) continue;
      if (hi[u] - lo[u] > range * z[u]) continue;  // straddles an edge: keep the measurement
      z[u] = n[u] / s[u];
    }
  }
}

}  // namespace rgbdmap
