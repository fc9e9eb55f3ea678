#include "rgbdmap/voxel_map.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdmap {
namespace {

constexpr int kBits = 21;
constexpr std::int64_t kOffset = std::int64_t{1} << (kBits - 1);  // maps [-2^20, 2^20) to [0, 2^21)
constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;

}  // namespace

VoxelMap::VoxelMap(double voxel_size)
    : voxel_size_(voxel_size), inv_voxel_size_(static_cast<float>(1.0 / voxel_size)) {}

bool VoxelMap::keyFor(const Eigen::Vector3f& p, std::uint64_t& key) const {
  key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const float scaled = std::floor(p[axis] * inv_voxel_size_);
    if (!(scaled >= -static_cast<float>(kOffset) && scaled < static_cast<float>(kOffset)))
      return false;  // also rejects NaN
    const auto index = static_cast<std::uint64_t>(static_cast<std::int64_t>(scaled) + kOffset);
    key |= index << (kBits * axis);
  }
  return true;
}

Eigen::Vector3i VoxelMap::unpack(std::uint64_t key) {
  Eigen::Vector3i v;
  for (int axis = 0; axis < 3; ++axis)
    v[axis] = static_cast<int>(static_cast<std::int64_t>((key >> (kBits * axis)) & kMask) - kOffset);
  return v;
}

void VoxelMap::integrate(const PointBatch& batch) {
  frame_sums_.clear();
  // Neighbouring pixels usually fall into the same voxel, so the last sum is remembered and
  // the lookup skipped for runs of equal keys. The pointer is refreshed after every lookup,
  // because an insertion may move the table's elements.
  std::uint64_t cached_key = 0;
  FrameSum* cached = nullptr;
  for (std::size_t i = 0; i < batch.size(); ++i) {
    std::uint64_t key;
    if (!keyFor(batch.positions[i], key)) {
      ++rejected_;
      continue;
    }
    if (!cached || key != cached_key) {
      cached = &frame_sums_[key];
      cached_key = key;
    }
    const float w = batch.weights[i];
    cached->weighted_position += w * batch.positions[i];
    cached->weighted_color += w * batch.colors[i];
    cached->weight += w;
    ++cached->points;
  }
  for (const auto& [key, sum] : frame_sums_) {
    Voxel& v = voxels_[key];
    const float total = v.weight + sum.weight;
    const float alpha = sum.weight / total;
    v.position += alpha * (sum.weighted_position / sum.weight - v.position);
    v.color += alpha * (sum.weighted_color / sum.weight - v.color);
    v.weight = total;
    v.observations += sum.points;
  }
}

void VoxelMap::extract(pcl::PointCloud<pcl::PointXYZRGB>& cloud,
                       std::uint32_t min_observations) const {
  cloud.clear();
  cloud.reserve(voxels_.size());
  for (const auto& [key, v] : voxels_) {
    if (v.observations < min_observations) continue;
    pcl::PointXYZRGB p;
    p.x = v.position.x();
    p.y = v.position.y();
    p.z = v.position.z();
    p.r = static_cast<std::uint8_t>(std::lround(std::clamp(v.color.x(), 0.0f, 255.0f)));
    p.g = static_cast<std::uint8_t>(std::lround(std::clamp(v.color.y(), 0.0f, 255.0f)));
    p.b = static_cast<std::uint8_t>(std::lround(std::clamp(v.color.z(), 0.0f, 255.0f)));
    cloud.push_back(p);
  }
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
}

}  // namespace rgbdmap
