#include "rgbdmap/mapping/point_merger.hpp"

#include <cmath>

namespace rgbdmap {
namespace {

// 21 bits per axis, as VoxelMap's keys: +-10 km at 1 cm. Points beyond are left out.
bool keyOf(const Eigen::Vector3f& p, double voxel, std::uint64_t& key) {
  constexpr std::int64_t kOffset = std::int64_t{1} << 20;
  key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double scaled = std::floor(static_cast<double>(p[axis]) / voxel) + kOffset;
    if (!(scaled >= 0 && scaled < 2.0 * kOffset)) return false;  // also NaN
    key |= static_cast<std::uint64_t>(scaled) << (21 * axis);
  }
  return true;
}

}  // namespace

void PointMerger::add(const SurfaceCloud& points, const Eigen::Isometry3d& pose) {
  const Eigen::Isometry3f moved = pose.cast<float>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const VoxelMap::SurfacePoint point = points[i];
    const Eigen::Vector3f p = moved * point.position;
    std::uint64_t key;
    if (!keyOf(p, voxel_size_, key)) continue;
    const auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(sums_.size()));
    if (inserted) sums_.emplace_back();
    Sum& sum = sums_[it->second];
    const float w = std::max(point.weight, 1e-6f);
    sum.position += w * p;
    sum.color += w * Eigen::Vector3f(point.r, point.g, point.b);
    sum.weight += w;
  }
}

void PointMerger::extract(MapCloud& cloud) const {
  cloud.clear();
  cloud.reserve(sums_.size());
  for (const Sum& sum : sums_) {
    const Eigen::Vector3f p = sum.position / sum.weight;
    const Eigen::Vector3f c = sum.color / sum.weight;
    pcl::PointXYZRGB point;
    point.x = p.x();
    point.y = p.y();
    point.z = p.z();
    point.r = static_cast<std::uint8_t>(std::lround(c.x()));
    point.g = static_cast<std::uint8_t>(std::lround(c.y()));
    point.b = static_cast<std::uint8_t>(std::lround(c.z()));
    cloud.push_back(point);
  }
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
}

}  // namespace rgbdmap
