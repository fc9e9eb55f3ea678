#include "rgbdmap/mapping/back_projector.hpp"

#include "rgbdmap/capture/lens_undistortion.hpp"

namespace rgbdmap {

BackProjector::BackProjector(const CameraIntrinsics& camera, bool undistort)
    : width_(camera.width), height_(camera.height), rays_(camera.width * camera.height) {
  if (undistort && camera.hasDistortion()) {
    std::vector<cv::Point2f> pixels, normalized;
    pixels.reserve(rays_.size());
    for (int v = 0; v < height_; ++v)
      for (int u = 0; u < width_; ++u)
        pixels.emplace_back(static_cast<float>(u), static_cast<float>(v));
    LensUndistortion::rays(camera, pixels, normalized);
    for (std::size_t i = 0; i < rays_.size(); ++i) rays_[i] = {normalized[i].x, normalized[i].y};
  } else {
    for (int v = 0; v < height_; ++v)
      for (int u = 0; u < width_; ++u)
        rays_[v * width_ + u] = {static_cast<float>((u - camera.cx) / camera.fx),
                                 static_cast<float>((v - camera.cy) / camera.fy)};
  }
}

void BackProjector::project(const cv::Mat& depth, const cv::Mat& color_bgr,
                            const Eigen::Isometry3d& pose, PointBatch& out) const {
  CV_Assert(depth.type() == CV_32FC1 && depth.cols == width_ && depth.rows == height_);
  CV_Assert(color_bgr.type() == CV_8UC3 && color_bgr.size() == depth.size());
  const Eigen::Matrix3f R = pose.linear().cast<float>();
  const Eigen::Vector3f t = pose.translation().cast<float>();
  const float sigma_at_1m = kinectDepthSigma(1.0f);
  for (int v = 0; v < height_; ++v) {
    const float* z_row = depth.ptr<float>(v);
    const cv::Vec3b* c_row = color_bgr.ptr<cv::Vec3b>(v);
    const Eigen::Vector2f* ray = rays_.data() + static_cast<std::size_t>(v) * width_;
    const bool odd_row = (v & 1) != 0;
    for (int u = 0; u < width_; ++u) {
      const float z = z_row[u];
      if (z <= 0.0f) continue;
      if ((odd_row || (u & 1) != 0) && z < subsample_below_depth_) continue;
      const Eigen::Vector3f p(ray[u].x() * z, ray[u].y() * z, z);
      out.positions.push_back(R * p + t);
      out.colors.emplace_back(c_row[u][2], c_row[u][1], c_row[u][0]);
      const float s = kinectDepthSigma(z) / sigma_at_1m;
      out.weights.push_back(1.0f / (s * s));
      out.pixels.push_back(v * width_ + u);
    }
  }
}

}  // namespace rgbdmap
