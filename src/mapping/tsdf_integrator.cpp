#include "rgbdmap/mapping/tsdf_integrator.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdmap/mapping/back_projector.hpp"

namespace rgbdmap {

float TsdfIntegrator::bandAt(float depth) const {
  return std::max(static_cast<float>(truncation),
                  static_cast<float>(truncation_sigmas) * kinectDepthSigma(depth));
}

namespace {

// Allocates the blocks along each sampled pixel's ray within the band around its depth.
void allocate(const TsdfIntegrator& tsdf, const cv::Mat& depth, const Eigen::Isometry3d& pose,
              VoxelMap& map) {
  const CameraIntrinsics& cam = tsdf.camera;
  const float block = static_cast<float>(map.voxelSize() * VoxelMap::kBlockEdge);
  const float inv_block = 1.0f / block;
  const Eigen::Matrix3f R = pose.linear().cast<float>();
  const Eigen::Vector3f t = pose.translation().cast<float>();
  const int stride = std::max(1, tsdf.allocation_stride);
  Eigen::Vector3i last(INT32_MIN, INT32_MIN, INT32_MIN);
  for (int v = 0; v < depth.rows; v += stride) {
    const float* row = depth.ptr<float>(v);
    for (int u = 0; u < depth.cols; u += stride) {
      const float d = row[u];
      if (!(d > 0.0f)) continue;
      const float band = tsdf.bandAt(d);
      const Eigen::Vector3f ray =
          R * Eigen::Vector3f(static_cast<float>((u - cam.cx) / cam.fx),
                              static_cast<float>((v - cam.cy) / cam.fy), 1.0f);
      // Steps of at most half a block along the ray, so that no block it crosses is skipped.
      const int steps = 1 + static_cast<int>(std::ceil(2.0f * band * ray.norm() / (0.5f * block)));
      for (int i = 0; i <= steps; ++i) {
        const float s = d - band + 2.0f * band * static_cast<float>(i) / static_cast<float>(steps);
        const Eigen::Vector3f p = (t + ray * s) * inv_block;
        const Eigen::Vector3i b(static_cast<int>(std::floor(p.x())),
                                static_cast<int>(std::floor(p.y())),
                                static_cast<int>(std::floor(p.z())));
        if (b == last) continue;
        last = b;
        map.touchBlock(b);
      }
    }
  }
}

std::uint8_t blend(std::uint8_t old_value, std::uint8_t new_value, float alpha) {
  const float mixed = old_value + alpha * (static_cast<float>(new_value) - old_value);
  return static_cast<std::uint8_t>(std::clamp(mixed + 0.5f, 0.0f, 255.0f));
}

}  // namespace

void TsdfIntegrator::integrate(const cv::Mat& depth, const cv::Mat& color_bgr,
                               const Eigen::Isometry3d& pose, VoxelMap& map) const {
  CV_Assert(depth.type() == CV_32FC1 && color_bgr.type() == CV_8UC3 &&
            color_bgr.size() == depth.size());
  map.beginIntegration();
  allocate(*this, depth, pose, map);

  const Eigen::Isometry3f world_to_camera = pose.inverse().cast<float>();
  const Eigen::Matrix3f Rcw = world_to_camera.linear();
  const float voxel = static_cast<float>(map.voxelSize());
  const Eigen::Vector3f dx = Rcw.col(0) * voxel, dy = Rcw.col(1) * voxel, dz = Rcw.col(2) * voxel;
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx) + 0.5f, cy = static_cast<float>(camera.cy) + 0.5f;
  const float width = static_cast<float>(depth.cols), height = static_cast<float>(depth.rows);
  const float sigma_at_1m = kinectDepthSigma(1.0f);
  constexpr int kEdge = VoxelMap::kBlockEdge;

  for (const std::uint32_t index : map.touchedBlocks()) {
    VoxelMap::Block& block = map.block(index);
    const Eigen::Vector3f origin =
        world_to_camera * ((block.origin.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * voxel);
    for (int z = 0; z < kEdge; ++z) {
      for (int y = 0; y < kEdge; ++y) {
        Eigen::Vector3f p = origin + static_cast<float>(y) * dy + static_cast<float>(z) * dz;
        VoxelMap::Voxel* row = block.voxels.data() + (z * kEdge + y) * kEdge;
        for (int x = 0; x < kEdge; ++x, p += dx) {
          if (p.z() <= 0.0f) continue;
          const float inv_z = 1.0f / p.z();
          const float u = fx * p.x() * inv_z + cx;  // + 0.5: truncation rounds to nearest
          const float v = fy * p.y() * inv_z + cy;
          if (!(u >= 0.0f && v >= 0.0f && u < width && v < height)) continue;
          const int ui = static_cast<int>(u), vi = static_cast<int>(v);
          const float d = depth.ptr<float>(vi)[ui];
          if (!(d > 0.0f)) continue;
          const float sdf = d - p.z();
          const float sigma = kinectDepthSigma(d);
          const float band = std::max(static_cast<float>(truncation),
                                      static_cast<float>(truncation_sigmas) * sigma);
          if (sdf < -band) continue;  // hidden behind the surface: nothing known
          const float s = sigma_at_1m / sigma;
          const float w = s * s;
          VoxelMap::Voxel& voxel_ref = row[x];
          const float total = voxel_ref.weight + w;
          const float alpha = w / total;
          voxel_ref.sdf += alpha * (std::min(sdf, band) - voxel_ref.sdf);
          voxel_ref.weight = total;
          if (sdf < band) {  // near the surface: its colour
            const cv::Vec3b& c = color_bgr.ptr<cv::Vec3b>(vi)[ui];
            voxel_ref.r = blend(voxel_ref.r, c[2], alpha);
            voxel_ref.g = blend(voxel_ref.g, c[1], alpha);
            voxel_ref.b = blend(voxel_ref.b, c[0], alpha);
          }
          if (voxel_ref.observations < 255) ++voxel_ref.observations;
        }
      }
    }
  }
  map.finishIntegration();
}

}  // namespace rgbdmap
