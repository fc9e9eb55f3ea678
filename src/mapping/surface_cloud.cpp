#include "rgbdmap/mapping/surface_cloud.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rgbdmap {
namespace {

constexpr float kSteps = 65535.0f;
constexpr float kWeightScale = 16.0f;

std::uint16_t quantise(float value, float origin, float step) {
  return static_cast<std::uint16_t>(std::clamp(std::lround((value - origin) / step), 0L, 65535L));
}

}  // namespace

SurfaceCloud::SurfaceCloud(const std::vector<VoxelMap::SurfacePoint>& points) {
  Eigen::Vector3f low = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f high = -low;
  std::size_t finite = 0;
  for (const VoxelMap::SurfacePoint& p : points) {
    if (!p.position.allFinite()) continue;
    low = low.cwiseMin(p.position);
    high = high.cwiseMax(p.position);
    ++finite;
  }
  if (finite == 0) return;
  origin_ = low;
  // A flat cloud still needs a non-zero step on its flat axis.
  step_ = ((high - low) / kSteps).cwiseMax(Eigen::Vector3f::Constant(1e-6f));
  if (step_.maxCoeff() > kMaxStep) {
    for (const VoxelMap::SurfacePoint& p : points)
      if (p.position.allFinite()) exact_.push_back(p);
    return;
  }
  points_.reserve(finite);
  for (const VoxelMap::SurfacePoint& p : points) {
    if (!p.position.allFinite()) continue;
    const float weight = std::min(p.weight * kWeightScale, 65535.0f);
    points_.push_back({quantise(p.position.x(), origin_.x(), step_.x()),
                       quantise(p.position.y(), origin_.y(), step_.y()),
                       quantise(p.position.z(), origin_.z(), step_.z()),
                       static_cast<std::uint16_t>(std::max(1.0f, std::round(weight))), p.r, p.g,
                       p.b});
  }
}

VoxelMap::SurfacePoint SurfaceCloud::operator[](std::size_t i) const {
  if (!exact_.empty()) return exact_[i];
  const Packed& q = points_[i];
  VoxelMap::SurfacePoint p;
  p.position = origin_ + step_.cwiseProduct(Eigen::Vector3f(q.x, q.y, q.z));
  p.weight = static_cast<float>(q.weight) / kWeightScale;
  p.r = q.r;
  p.g = q.g;
  p.b = q.b;
  return p;
}

}  // namespace rgbdmap
