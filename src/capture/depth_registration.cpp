#include "rgbdmap/capture/depth_registration.hpp"

#include <cmath>

#include "rgbdmap/capture/lens_undistortion.hpp"

namespace rgbdmap {

DepthRegistration::DepthRegistration(const CameraOptions& camera)
    : color_(camera), depth_(camera.depthCamera()), color_from_depth_(camera.colorFromDepth()) {}

void DepthRegistration::apply(cv::Mat& depth) {
  const int w = depth.cols, h = depth.rows;
  if (rays_.size() != static_cast<std::size_t>(w) * h) {
    rays_.resize(static_cast<std::size_t>(w) * h);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u)
        rays_[static_cast<std::size_t>(v) * w + u] = {
            static_cast<float>((u - depth_.cx) / depth_.fx),
            static_cast<float>((v - depth_.cy) / depth_.fy)};
  }
  // A new image each time: the frame's own may still be shared (a keyframe kept, a source's cache).
  cv::Mat registered(color_.height, color_.width, CV_32FC1, cv::Scalar(0.0f));
  const Eigen::Matrix3f R = color_from_depth_.linear().cast<float>();
  const Eigen::Vector3f t = color_from_depth_.translation().cast<float>();
  const bool distorted = color_.hasDistortion();
  const float fx = static_cast<float>(color_.fx), fy = static_cast<float>(color_.fy);
  const float cx = static_cast<float>(color_.cx), cy = static_cast<float>(color_.cy);
  for (int v = 0; v < h; ++v) {
    const float* z_row = depth.ptr<float>(v);
    for (int u = 0; u < w; ++u) {
      const float z = z_row[u];
      if (!(z > 0.0f)) continue;
      const Eigen::Vector2f& ray = rays_[static_cast<std::size_t>(v) * w + u];
      const Eigen::Vector3f p = R * Eigen::Vector3f(ray.x() * z, ray.y() * z, z) + t;
      if (p.z() <= 0.0f) continue;
      float x = p.x() / p.z(), y = p.y() / p.z();
      // Through the colour lens: the colour image is the distorted one.
      if (distorted) LensUndistortion::distortRay(color_, x, y);
      const int cu = static_cast<int>(std::lround(fx * x + cx));
      const int cv = static_cast<int>(std::lround(fy * y + cy));
      if (cu < 0 || cv < 0 || cu >= color_.width || cv >= color_.height) continue;
      float& out = registered.at<float>(cv, cu);
      if (out == 0.0f || p.z() < out) out = p.z();  // the nearest surface hides the rest
    }
  }
  // A surface seen more closely by the colour camera spreads over more pixels than it had: fill
  // the one-pixel cracks between two measured neighbours on the same surface.
  for (int v = 0; v < registered.rows; ++v) {
    float* row = registered.ptr<float>(v);
    for (int u = 1; u + 1 < registered.cols; ++u) {
      if (row[u] != 0.0f || row[u - 1] == 0.0f || row[u + 1] == 0.0f) continue;
      if (std::abs(row[u - 1] - row[u + 1]) < 0.02f * row[u - 1])
        row[u] = 0.5f * (row[u - 1] + row[u + 1]);
    }
  }
  depth = registered;
}

}  // namespace rgbdmap
