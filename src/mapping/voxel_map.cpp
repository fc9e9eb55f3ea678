#include "rgbdmap/mapping/voxel_map.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdmap {
namespace {

constexpr int kBits = 21;
constexpr std::int64_t kOffset = std::int64_t{1} << (kBits - 1);  // maps [-2^20, 2^20) to [0, 2^21)
constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;

// Voxel coordinates shifted to [0, 2^21) per axis, or false outside the key range (or NaN).
// Shifted first, the value is positive, so truncation is floor (cheaper than std::floor); in
// double, the shift loses no fraction.
bool voxelIndex(const Eigen::Vector3f& p, double inv_voxel_size, std::uint64_t index[3]) {
  for (int axis = 0; axis < 3; ++axis) {
    const double shifted = static_cast<double>(p[axis]) * inv_voxel_size + kOffset;
    if (!(shifted >= 0.0 && shifted < 2.0 * kOffset)) return false;  // also rejects NaN
    index[axis] = static_cast<std::uint64_t>(shifted);
  }
  return true;
}

}  // namespace

VoxelMap::VoxelMap(double voxel_size, std::uint32_t min_observations)
    : voxel_size_(voxel_size),
      inv_voxel_size_(1.0 / voxel_size),
      min_observations_(std::max<std::uint32_t>(min_observations, 1)) {}

bool VoxelMap::keyFor(const Eigen::Vector3f& p, std::uint64_t& key) const {
  std::uint64_t index[3];
  key = 0;
  if (!voxelIndex(p, inv_voxel_size_, index)) return false;
  for (int axis = 0; axis < 3; ++axis) key |= index[axis] << (kBits * axis);
  return true;
}

Eigen::Vector3i VoxelMap::unpack(std::uint64_t key) {
  Eigen::Vector3i v;
  for (int axis = 0; axis < 3; ++axis)
    v[axis] =
        static_cast<int>(static_cast<std::int64_t>((key >> (kBits * axis)) & kMask) - kOffset);
  return v;
}

bool VoxelMap::slotOf(const Eigen::Vector3f& p, std::uint32_t& slot) {
  std::uint64_t index[3];
  if (!voxelIndex(p, inv_voxel_size_, index)) return false;
  constexpr std::uint64_t kLocalMask = (1u << kBlockBits) - 1;
  std::uint64_t block_key = 0;
  std::uint32_t local = 0;
  for (int axis = 0; axis < 3; ++axis) {
    block_key |= (index[axis] >> kBlockBits) << (kBits * axis);
    local |= static_cast<std::uint32_t>(index[axis] & kLocalMask) << (kBlockBits * axis);
  }
  if (block_key != last_block_key_ || last_block_ == UINT32_MAX) {
    const auto [it, inserted] =
        block_index_.try_emplace(block_key, static_cast<std::uint32_t>(blocks_.size()));
    if (inserted) blocks_.emplace_back().fill(0);
    last_block_key_ = block_key;
    last_block_ = it->second;
  }
  slot = last_block_ * kBlockVoxels + local;
  return true;
}

void VoxelMap::integrate(const PointBatch& batch) {
  // Three passes over the points, so that the memory each one reads (cold, for a large map) can
  // be prefetched a few points ahead instead of stalling on one cache miss after the other.
  constexpr std::size_t kAhead = 16;
  constexpr std::uint32_t kRejected = UINT32_MAX;
  const std::size_t n = batch.size();
  point_slots_.resize(n);
  point_voxels_.resize(n);
  // 1. The slot of each point's voxel (a hash lookup per block, not per point).
  for (std::size_t i = 0; i < n; ++i) {
    if (!slotOf(batch.positions[i], point_slots_[i])) {
      ++rejected_;
      point_slots_[i] = kRejected;
    }
  }
  // 2. The voxel of each slot, created on first sight (in point order: deterministic).
  std::uint32_t* slots = blocks_.empty() ? nullptr : blocks_.front().data();
  for (std::size_t i = 0; i < n; ++i) {
    if (i + kAhead < n && point_slots_[i + kAhead] != kRejected)
      __builtin_prefetch(slots + point_slots_[i + kAhead]);
    if (point_slots_[i] == kRejected) continue;
    std::uint32_t& slot = slots[point_slots_[i]];
    if (slot == 0) {
      voxels_.emplace_back();
      slot = static_cast<std::uint32_t>(voxels_.size());
    }
    point_voxels_[i] = slot - 1;
  }
  // 3. The weighted running mean: after the update, position = sum(w p) / sum(w).
  for (std::size_t i = 0; i < n; ++i) {
    if (i + kAhead < n && point_slots_[i + kAhead] != kRejected)
      __builtin_prefetch(&voxels_[point_voxels_[i + kAhead]]);
    if (point_slots_[i] == kRejected) continue;
    Voxel& v = voxels_[point_voxels_[i]];
    const float w = batch.weights[i];
    v.weight += w;
    const float alpha = w / v.weight;
    v.position += alpha * (batch.positions[i] - v.position);
    v.color += alpha * (batch.colors[i] - v.color);
    if (++v.observations == min_observations_) ++points_;
  }
}

void VoxelMap::extract(pcl::PointCloud<pcl::PointXYZRGB>& cloud,
                       std::uint32_t min_observations) const {
  cloud.clear();
  cloud.reserve(voxels_.size());
  for (const Voxel& v : voxels_) {
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
