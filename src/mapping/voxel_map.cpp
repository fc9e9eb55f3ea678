#include "rgbdmap/mapping/voxel_map.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdmap {
namespace {

constexpr std::size_t kCountBlocksPerTask = 64;  // blocks counted per task
constexpr int kBits = 21;
constexpr std::int64_t kOffset = std::int64_t{1} << (kBits - 1);  // maps [-2^20, 2^20) to [0, 2^21)
constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;

// A surface voxel's point, for either point type (pcl::PointXYZRGB or PackedMapPoint).
template <typename Point>
Point surfacePoint(const Eigen::Vector3f& p, const VoxelMap::Voxel& v) {
  return mapPoint<Point>(p.x(), p.y(), p.z(), v.r, v.g, v.b);
}

}  // namespace

const Eigen::Vector3i VoxelMap::kNoBlock(INT32_MIN, INT32_MIN, INT32_MIN);

VoxelMap::VoxelMap(double voxel_size, std::uint32_t min_observations)
    : voxel_size_(voxel_size),
      min_observations_(std::clamp<std::uint32_t>(min_observations, 1, 255)) {}

std::size_t VoxelMap::memoryBytes() const {
  return blocks_.capacity() * sizeof(Block) +
         block_index_.bucket_count() * (sizeof(std::uint64_t) + sizeof(std::uint32_t) + 8);
}

bool VoxelMap::keyFor(const Eigen::Vector3f& p, std::uint64_t& key) const {
  Eigen::Vector3i coords;
  for (int axis = 0; axis < 3; ++axis) {
    const double scaled = std::floor(static_cast<double>(p[axis]) / voxel_size_);
    if (!(std::abs(scaled) < static_cast<double>(kOffset))) {  // also rejects NaN
      key = 0;
      return false;
    }
    coords[axis] = static_cast<int>(scaled);
  }
  return pack(coords, key);
}

bool VoxelMap::pack(const Eigen::Vector3i& coords, std::uint64_t& key) {
  key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t shifted = static_cast<std::int64_t>(coords[axis]) + kOffset;
    if (shifted < 0 || shifted >= 2 * kOffset) return false;
    key |= static_cast<std::uint64_t>(shifted) << (kBits * axis);
  }
  return true;
}

Eigen::Vector3i VoxelMap::unpack(std::uint64_t key) {
  Eigen::Vector3i v;
  for (int axis = 0; axis < 3; ++axis)
    v[axis] =
        static_cast<int>(static_cast<std::int64_t>((key >> (kBits * axis)) & kMask) - kOffset);
  return v;
}

std::uint32_t VoxelMap::touchBlock(const Eigen::Vector3i& block_coords) {
  std::uint64_t key;
  if (!pack(block_coords, key)) return UINT32_MAX;
  const std::uint32_t slot =
      free_.empty() ? static_cast<std::uint32_t>(blocks_.size()) : free_.back();
  if (allowed_ && block_index_.find(key) == block_index_.end() && !allowed_(block_coords))
    return UINT32_MAX;
  const auto [it, inserted] = block_index_.try_emplace(key, slot);
  if (inserted) {
    if (free_.empty()) {
      blocks_.emplace_back();
      coordinates_.push_back(block_coords);
    } else {
      free_.pop_back();
      blocks_[slot] = Block{};
      coordinates_[slot] = block_coords;
    }
    blocks_[slot].origin = block_coords * kBlockEdge;
    link(slot, block_coords);
  }
  touchExisting(it->second);
  return it->second;
}

void VoxelMap::link(std::uint32_t index, const Eigen::Vector3i& block_coords) {
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      Eigen::Vector3i at = block_coords;
      at[axis] += side == 0 ? -1 : 1;
      std::uint64_t key;
      if (!pack(at, key)) continue;
      const auto it = block_index_.find(key);
      if (it == block_index_.end()) continue;
      blocks_[index].neighbours[2 * axis + side] = it->second;
      blocks_[it->second].neighbours[2 * axis + (1 - side)] = index;
    }
  }
}

void VoxelMap::touchExisting(std::uint32_t index) {
  Block& b = blocks_[index];
  if (b.touched_in != integration_) {
    b.touched_in = integration_;
    touched_.push_back(index);
  }
}

void VoxelMap::clear() {
  blocks_.clear();
  block_index_.clear();
  coordinates_.clear();
  free_.clear();
  touched_.clear();
  count_due_.clear();
  points_ = 0;
  integration_ = 0;
}

std::size_t VoxelMap::pruneAwayFromSurfaces(std::uint64_t idle, float clearance) {
  std::size_t freed = 0;
  for (std::uint32_t i = 0; i < blocks_.size(); ++i) {
    Block& b = blocks_[i];
    if (!b.in_use || b.touched_in + idle >= integration_) continue;
    // Every observed voxel at least `clearance` on one side: in front (+1) or behind (-1).
    const auto all_beyond = [&](float side) {
      return std::all_of(b.voxels.begin(), b.voxels.end(), [&](const Voxel& v) {
        return !v.observed() || side * v.sdf() >= clearance;
      });
    };
    if (!all_beyond(1.0f) && !all_beyond(-1.0f)) continue;
    release(i);
    ++freed;
  }
  // Freed blocks may still be listed for counting: they count nothing now.
  return freed;
}

void VoxelMap::release(std::uint32_t i) {
  Block& b = blocks_[i];
  std::uint64_t key;
  pack(coordinates_[i], key);
  block_index_.erase(key);
  points_ -= b.surface_points;
  b.surface_points = 0;
  b.in_use = false;
  for (int n = 0; n < 6; ++n) {
    if (b.neighbours[n] != kNone) blocks_[b.neighbours[n]].neighbours[n ^ 1] = kNone;
    b.neighbours[n] = kNone;
  }
  coordinates_[i] = kNoBlock;
  free_.push_back(i);
}

void VoxelMap::replaceRegion(const VoxelMap& from,
                             const std::function<bool(const Eigen::Vector3i&)>& in) {
  beginIntegration();
  for (std::uint32_t i = 0; i < blocks_.size(); ++i) {
    if (!blocks_[i].in_use || !in(coordinates_[i])) continue;
    // Its neighbours outside the region lose the voxels they compared theirs with: counted again.
    for (const std::uint32_t n : blocks_[i].neighbours)
      if (n != kNone && !in(coordinates_[n])) touchExisting(n);
    release(i);
  }
  for (std::uint32_t j = 0; j < from.blocks_.size(); ++j) {
    const Block& b = from.blocks_[j];
    if (!b.in_use || !in(from.coordinates_[j])) continue;
    const std::uint32_t index = touchBlock(from.coordinates_[j]);
    if (index != kNone) blocks_[index].voxels = b.voxels;
  }
  finishIntegration();
}

VoxelMap::Neighbours VoxelMap::neighboursOf(const Block& block) const {
  Neighbours n;
  for (int i = 0; i < 6; ++i)
    n[i] = block.neighbours[i] == kNone ? nullptr : &blocks_[block.neighbours[i]];
  return n;
}

template <typename Emit>
void VoxelMap::forEachSurfaceVoxel(const Block& block, const Neighbours& neighbours,
                                   Emit&& emit) const {
  constexpr int kEdge = kBlockEdge;
  const float voxel = static_cast<float>(voxel_size_);
  // The voxel one step from (x, y, z) along `axis` (side 0: -1, 1: +1), in this block or the
  // next one; nullptr where there is none or it was never observed.
  auto neighbour = [&](int x, int y, int z, int axis, int side) -> const Voxel* {
    int at[3] = {x, y, z};
    at[axis] += side == 0 ? -1 : 1;
    const Block* in = &block;
    if (at[axis] < 0 || at[axis] >= kEdge) {
      in = neighbours[2 * axis + side];
      if (in == nullptr) return nullptr;
      at[axis] &= kEdge - 1;
    }
    const Voxel& v = in->voxels[(at[2] * kEdge + at[1]) * kEdge + at[0]];
    return v.observed() ? &v : nullptr;
  };
  for (int z = 0; z < kEdge; ++z) {
    for (int y = 0; y < kEdge; ++y) {
      for (int x = 0; x < kEdge; ++x) {
        const Voxel& v = block.voxels[(z * kEdge + y) * kEdge + x];
        // The nearer voxel of a crossing is within about half a voxel of the surface (a little
        // more along an oblique line of sight); farther ones cannot be the nearer of a pair.
        if (!v.observed() || v.observations < min_observations_ || std::abs(v.sdf()) >= voxel)
          continue;
        const bool front = v.sdf() >= 0.0f;
        bool surface = false;
        const Voxel* lower[3];
        const Voxel* upper[3];
        for (int axis = 0; axis < 3; ++axis) {
          lower[axis] = neighbour(x, y, z, axis, 0);
          upper[axis] = neighbour(x, y, z, axis, 1);
          for (const Voxel* n : {lower[axis], upper[axis]}) {
            if (n == nullptr || (n->sdf() >= 0.0f) == front) continue;
            const float own = std::abs(v.sdf()), other = std::abs(n->sdf());
            if (own < other || (own == other && front)) surface = true;
          }
        }
        if (!surface) continue;
        Eigen::Vector3f gradient;
        for (int axis = 0; axis < 3; ++axis) {
          if (lower[axis] && upper[axis])
            gradient[axis] = (upper[axis]->sdf() - lower[axis]->sdf()) / (2.0f * voxel);
          else if (upper[axis])
            gradient[axis] = (upper[axis]->sdf() - v.sdf()) / voxel;
          else if (lower[axis])
            gradient[axis] = (v.sdf() - lower[axis]->sdf()) / voxel;
          else
            gradient[axis] = 0.0f;
        }
        Eigen::Vector3f p = (block.origin + Eigen::Vector3i(x, y, z)).cast<float>();
        p = (p + Eigen::Vector3f::Constant(0.5f)) * voxel;
        // Onto the zero level of the locally linear field, at most a voxel away.
        const float g2 = gradient.squaredNorm();
        if (g2 > 1e-6f) {
          Eigen::Vector3f step = -v.sdf() * gradient / g2;
          const float length = step.norm();
          if (length > voxel) step *= voxel / length;
          p += step;
        }
        emit(p, v);
      }
    }
  }
}

void VoxelMap::finishIntegration() {
  auto due = [&](std::uint32_t i) {
    Block& b = blocks_[i];
    if (b.count_due) return;
    b.count_due = true;
    count_due_.push_back(i);
  };
  for (const std::uint32_t i : touched_) {
    due(i);
    for (const std::uint32_t n : blocks_[i].neighbours)
      if (n != kNone) due(n);
  }
  touched_.clear();
}

std::size_t VoxelMap::pointCount(WorkerPool* pool) {
  // Each block is counted by one task, reading its neighbours' voxels and writing only its own
  // count; the tasks' totals are then added (integers: the order does not matter).
  const std::size_t tasks = (count_due_.size() + kCountBlocksPerTask - 1) / kCountBlocksPerTask;
  std::vector<std::int64_t> changes(tasks, 0);  // at most once a second: allocating is fine
  runTasks(pool, tasks, [&](std::size_t task) {
    const std::size_t first = task * kCountBlocksPerTask;
    const std::size_t last = std::min(count_due_.size(), first + kCountBlocksPerTask);
    std::int64_t change = 0;
    for (std::size_t k = first; k < last; ++k) {
      Block& b = blocks_[count_due_[k]];
      b.count_due = false;
      if (!b.in_use) continue;
      std::uint32_t count = 0;
      forEachSurfaceVoxel(b, neighboursOf(b),
                          [&](const Eigen::Vector3f&, const Voxel&) { ++count; });
      change += static_cast<std::int64_t>(count) - b.surface_points;
      b.surface_points = count;
    }
    changes[task] = change;
  });
  for (const std::int64_t change : changes)
    points_ = static_cast<std::size_t>(static_cast<std::int64_t>(points_) + change);
  count_due_.clear();
  return points_;
}

template <typename Emit>
void VoxelMap::forEachPoint(Emit&& emit) const {
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    const Block& b = blocks_[i];
    if (!b.in_use || (b.surface_points == 0 && !b.count_due)) continue;
    forEachSurfaceVoxel(b, neighboursOf(b), emit);
  }
}

void VoxelMap::extract(pcl::PointCloud<pcl::PointXYZRGB>& cloud) const {
  cloud.clear();
  cloud.reserve(pointsToReserve());
  forEachPoint([&](const Eigen::Vector3f& p, const Voxel& v) {
    cloud.push_back(surfacePoint<pcl::PointXYZRGB>(p, v));
  });
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
}

void VoxelMap::extract(std::vector<PackedMapPoint>& points) const {
  points.clear();
  points.reserve(pointsToReserve());
  forEachPoint([&](const Eigen::Vector3f& p, const Voxel& v) {
    points.push_back(surfacePoint<PackedMapPoint>(p, v));
  });
}

}  // namespace rgbdmap
