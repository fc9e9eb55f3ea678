#include "rgbdmap/mapping/voxel_map.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

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
         block_index_.bucket_count() * (sizeof(std::uint64_t) + sizeof(std::uint32_t) + 8) +
         stored_.memoryBytes();
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
  const auto it = block_index_.find(key);
  std::uint32_t index;
  if (it != block_index_.end()) {
    index = it->second;
  } else if (!stored_.empty() && stored_.find(key) != nullptr) {
    index = restore(key, block_coords);
  } else {
    if (allowed_ && !allowed_(block_coords)) return UINT32_MAX;
    index = place(key, block_coords);
  }
  touchExisting(index);
  return index;
}

std::uint32_t VoxelMap::place(std::uint64_t key, const Eigen::Vector3i& block_coords) {
  std::uint32_t slot;
  if (free_.empty()) {
    slot = static_cast<std::uint32_t>(blocks_.size());
    blocks_.emplace_back();
    coordinates_.push_back(block_coords);
  } else {
    slot = free_.back();
    free_.pop_back();
    blocks_[slot] = Block{};
    coordinates_[slot] = block_coords;
  }
  blocks_[slot].origin = block_coords * kBlockEdge;
  block_index_.emplace(key, slot);
  link(slot, block_coords);
  return slot;
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
  if (b.touched_in == integration_) return;
  b.touched_in = integration_;
  touched_.push_back(index);
  if (stored_.empty()) return;
  // Its neighbours on disk come back: the surface they write depends on this block's voxels, and
  // their counts on disk would go stale.
  for (int n = 0; n < 6; ++n) {
    if (b.neighbours[n] != kNone) continue;
    Eigen::Vector3i at = coordinates_[index];
    at[n / 2] += n % 2 == 0 ? -1 : 1;
    std::uint64_t key;
    if (pack(at, key) && stored_.find(key) != nullptr) restore(key, at);
  }
}

std::uint32_t VoxelMap::restore(std::uint64_t key, const Eigen::Vector3i& block_coords) {
  const BlockStore::Stored stored = *stored_.find(key);
  stored_.erase(key);
  noteStored(key, false);
  const std::uint32_t index = place(key, block_coords);
  Block& b = blocks_[index];
  std::vector<std::uint8_t> scratch;
  std::string error;
  b.touched_in = stored.touched_in;
  if (stored_.read(stored, b.voxels, scratch, error)) {
    b.surface_points = stored.surface_points;
  } else {
    // Lost: the block is fused anew from what is seen next.
    spdlog::error("{}: a block of the map at {} {} {} is lost", error, block_coords.x(),
                  block_coords.y(), block_coords.z());
    b.voxels.fill(Voxel{});
    points_ -= stored.surface_points;
  }
  return index;
}

const VoxelMap::Block* VoxelMap::readStored(std::uint64_t key, const Eigen::Vector3i& block_coords,
                                            BlockCache& cache) const {
  const auto cached = cache.blocks_.find(key);
  if (cached != cache.blocks_.end()) return cached->second.get();
  const BlockStore::Stored* stored = stored_.find(key);
  if (stored == nullptr) return nullptr;
  auto b = std::make_unique<Block>();
  b->origin = block_coords * kBlockEdge;
  b->surface_points = stored->surface_points;
  b->in_use = false;  // in no slot
  std::string error;
  if (!stored_.read(*stored, b->voxels, cache.scratch_, error)) {
    spdlog::error("{}: a block of the map at {} {} {} is left out", error, block_coords.x(),
                  block_coords.y(), block_coords.z());
    return nullptr;
  }
  return cache.blocks_.emplace(key, std::move(b)).first->second.get();
}

const VoxelMap::Block* VoxelMap::findBlock(const Eigen::Vector3i& block_coords,
                                           BlockCache& cache) const {
  std::uint64_t key;
  if (!pack(block_coords, key)) return nullptr;
  const auto it = block_index_.find(key);
  if (it != block_index_.end()) return &blocks_[it->second];
  return stored_.empty() ? nullptr : readStored(key, block_coords, cache);
}

std::vector<Eigen::Vector3i> VoxelMap::allBlockCoordinates() const {
  std::vector<Eigen::Vector3i> all;
  all.reserve(blockCount() + stored_.size());
  for (const Eigen::Vector3i& c : coordinates_)
    if (c != kNoBlock) all.push_back(c);
  for (const auto& [key, stored] : stored_.blocks()) all.push_back(unpack(key));
  return all;
}

std::size_t VoxelMap::keepWithin(std::size_t max_blocks, std::uint64_t min_idle) {
  if (max_blocks == 0 || blockCount() <= max_blocks || store_refused_) return 0;
  // The least recently updated first; among those updated together, in key order, which keeps
  // blocks next to one another along x together on disk.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> idle;  // (integration, key)
  for (std::uint32_t i = 0; i < blocks_.size(); ++i) {
    const Block& b = blocks_[i];
    std::uint64_t key;
    if (b.in_use && b.touched_in + min_idle < integration_ && pack(coordinates_[i], key))
      idle.emplace_back(b.touched_in, key);
  }
  const std::size_t wanted = std::min(idle.size(), blockCount() - (max_blocks - max_blocks / 4));
  std::partial_sort(idle.begin(), idle.begin() + static_cast<std::ptrdiff_t>(wanted), idle.end());
  BlockCache cache;
  std::size_t moved = 0;
  for (std::size_t k = 0; k < wanted; ++k) {
    cache.trim();
    if (!store(block_index_.at(idle[k].second), cache)) break;
    ++moved;
  }
  return moved;
}

bool VoxelMap::store(std::uint32_t index, BlockCache& cache) {
  Block& b = blocks_[index];
  // Its count is current when it goes: no neighbour changes while it is on disk.
  if (b.count_due) recount(b, &cache);
  std::uint64_t key;
  pack(coordinates_[index], key);
  std::string error;
  if (!stored_.put(key, b.voxels, b.surface_points, b.touched_in, error)) {
    spdlog::warn("{}: the map stays in memory from now on", error);
    store_refused_ = true;
    return false;
  }
  noteStored(key, true);
  unplace(index);
  return true;
}

void VoxelMap::noteStored(std::uint64_t key, bool stored) {
  std::uint64_t cell;
  pack(cellOf(unpack(key)), cell);
  std::vector<std::uint64_t>& keys = stored_cells_[cell];
  if (stored) {
    keys.push_back(key);
    return;
  }
  const auto it = std::find(keys.begin(), keys.end(), key);
  if (it != keys.end()) {
    *it = keys.back();
    keys.pop_back();
  }
  if (keys.empty()) stored_cells_.erase(cell);
}

std::vector<Eigen::Vector3i> VoxelMap::storedNear(const Eigen::Vector3f& centre,
                                                  float radius) const {
  std::vector<Eigen::Vector3i> near;
  const float cell_edge = static_cast<float>(cellSize(voxel_size_));
  const float reach = radius + 0.5f * std::sqrt(3.0f) * cell_edge;
  for (const auto& [cell, keys] : stored_cells_) {
    const Eigen::Vector3f middle =
        (unpack(cell).cast<float>() + Eigen::Vector3f::Constant(0.5f)) * cell_edge;
    if ((middle - centre).squaredNorm() > reach * reach) continue;
    for (const std::uint64_t key : keys) near.push_back(unpack(key));
  }
  return near;
}

void VoxelMap::recount(Block& b, BlockCache* cache) {
  b.count_due = false;
  std::uint32_t count = 0;
  forEachSurfaceVoxel(b, neighboursOf(b, cache),
                      [&](const Eigen::Vector3f&, const Voxel&) { ++count; });
  points_ = points_ + count - b.surface_points;
  b.surface_points = count;
}

void VoxelMap::clear() {
  stored_.clear();
  stored_cells_.clear();
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
  std::vector<Eigen::Vector3i> gone;
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
    gone.push_back(coordinates_[i]);
    release(i);
  }
  // Those on disk alike, by the distances noted when they went (no block changes on disk).
  const float step = Voxel::kSdfStep;
  std::vector<std::uint64_t> idle_stored;
  for (const auto& [key, stored] : stored_.blocks())
    if (stored.touched_in + idle < integration_ &&
        (stored.least_sdf > stored.greatest_sdf ||  // none observed
         static_cast<float>(stored.least_sdf) * step >= clearance ||
         static_cast<float>(stored.greatest_sdf) * step <= -clearance))
      idle_stored.push_back(key);
  for (const std::uint64_t key : idle_stored) {
    points_ -= stored_.find(key)->surface_points;
    stored_.erase(key);
    noteStored(key, false);
    gone.push_back(unpack(key));
  }
  // A voxel beside a freed one may have been a surface voxel by comparison with it.
  recountAround(gone);
  // Freed blocks may still be listed for counting: they count nothing now.
  return gone.size();
}

void VoxelMap::release(std::uint32_t i) {
  Block& b = blocks_[i];
  points_ -= b.surface_points;
  b.surface_points = 0;
  unplace(i);
}

void VoxelMap::unplace(std::uint32_t i) {
  Block& b = blocks_[i];
  std::uint64_t key;
  pack(coordinates_[i], key);
  block_index_.erase(key);
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
  // The blocks next to the region, outside it, lose the voxels they compared theirs with: they
  // are counted again (in memory: those on disk come back).
  const auto touchAround = [&](const Eigen::Vector3i& coords) {
    for (int n = 0; n < 6; ++n) {
      Eigen::Vector3i at = coords;
      at[n / 2] += n % 2 == 0 ? -1 : 1;
      std::uint64_t key;
      if (in(at) || !pack(at, key)) continue;
      const auto it = block_index_.find(key);
      if (it != block_index_.end())
        touchExisting(it->second);
      else if (!stored_.empty() && stored_.find(key) != nullptr)
        touchExisting(restore(key, at));
    }
  };
  // Every block of the region goes before any around it is touched: touching one brings its
  // neighbours back from disk, which must not bring back the region's.
  std::vector<std::uint64_t> stored_in;
  for (const auto& [key, stored] : stored_.blocks())
    if (in(unpack(key))) stored_in.push_back(key);
  std::vector<Eigen::Vector3i> gone;
  for (const std::uint64_t key : stored_in) {
    points_ -= stored_.find(key)->surface_points;
    stored_.erase(key);
    noteStored(key, false);
    gone.push_back(unpack(key));
  }
  for (std::uint32_t i = 0; i < blocks_.size(); ++i) {
    if (!blocks_[i].in_use || !in(coordinates_[i])) continue;
    gone.push_back(coordinates_[i]);
    release(i);
  }
  for (const Eigen::Vector3i& coords : gone) touchAround(coords);
  const auto take = [&](const Eigen::Vector3i& coords, const Block& b) {
    const std::uint32_t index = touchBlock(coords);
    if (index != kNone) blocks_[index].voxels = b.voxels;
  };
  for (std::uint32_t j = 0; j < from.blocks_.size(); ++j)
    if (from.blocks_[j].in_use && in(from.coordinates_[j]))
      take(from.coordinates_[j], from.blocks_[j]);
  BlockCache cache;
  for (const auto& [key, stored] : from.stored_.blocks()) {
    const Eigen::Vector3i coords = unpack(key);
    if (!in(coords)) continue;
    cache.trim();
    if (const Block* b = from.readStored(key, coords, cache)) take(coords, *b);
  }
  finishIntegration();
}

VoxelMap::Neighbours VoxelMap::neighboursOf(const Block& block, BlockCache* cache) const {
  Neighbours n;
  const bool any_stored = cache != nullptr && !stored_.empty();
  for (int i = 0; i < 6; ++i) {
    if (block.neighbours[i] != kNone) {
      n[i] = &blocks_[block.neighbours[i]];
    } else if (any_stored) {
      // Linked neighbours are all those in memory, but a block read back from disk has no links.
      Eigen::Vector3i at = block.origin / kBlockEdge;
      at[i / 2] += i % 2 == 0 ? -1 : 1;
      n[i] = findBlock(at, *cache);
    } else {
      n[i] = nullptr;
    }
  }
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

void VoxelMap::markDue(std::uint32_t i) {
  Block& b = blocks_[i];
  if (b.count_due) return;
  b.count_due = true;
  count_due_.push_back(i);
}

void VoxelMap::finishIntegration() {
  for (const std::uint32_t i : touched_) {
    markDue(i);
    for (const std::uint32_t n : blocks_[i].neighbours)
      if (n != kNone) markDue(n);
  }
  touched_.clear();
}

void VoxelMap::recountAround(const std::vector<Eigen::Vector3i>& gone) {
  BlockCache cache;
  for (const Eigen::Vector3i& coords : gone) {
    for (int n = 0; n < 6; ++n) {
      Eigen::Vector3i at = coords;
      at[n / 2] += n % 2 == 0 ? -1 : 1;
      std::uint64_t key;
      if (!pack(at, key)) continue;
      const auto it = block_index_.find(key);
      if (it != block_index_.end()) {
        markDue(it->second);
        continue;
      }
      const BlockStore::Stored* stored = stored_.empty() ? nullptr : stored_.find(key);
      if (stored == nullptr) continue;
      cache.trim();
      const Block* b = readStored(key, at, cache);
      if (b == nullptr) continue;
      std::uint32_t count = 0;
      forEachSurfaceVoxel(*b, neighboursOf(*b, &cache),
                          [&](const Eigen::Vector3f&, const Voxel&) { ++count; });
      points_ = points_ + count - stored->surface_points;
      stored_.setSurfacePoints(key, count);
    }
  }
}

std::size_t VoxelMap::pointCount(WorkerPool* pool) {
  // A slot freed and used again can be listed twice: each block is counted by one task only.
  std::sort(count_due_.begin(), count_due_.end());
  count_due_.erase(std::unique(count_due_.begin(), count_due_.end()), count_due_.end());
  // Each block is counted by one task, reading its neighbours' voxels and writing only its own
  // count; the tasks' totals are then added (integers: the order does not matter).
  const std::size_t tasks = (count_due_.size() + kCountBlocksPerTask - 1) / kCountBlocksPerTask;
  std::vector<std::int64_t> changes(tasks, 0);  // at most once a second: allocating is fine
  runTasks(pool, tasks, [&](std::size_t task) {
    const std::size_t first = task * kCountBlocksPerTask;
    const std::size_t last = std::min(count_due_.size(), first + kCountBlocksPerTask);
    std::int64_t change = 0;
    BlockCache cache;
    for (std::size_t k = first; k < last; ++k) {
      Block& b = blocks_[count_due_[k]];
      b.count_due = false;
      if (!b.in_use) continue;
      cache.trim();
      std::uint32_t count = 0;
      forEachSurfaceVoxel(b, neighboursOf(b, &cache),
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
  BlockCache cache;
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    const Block& b = blocks_[i];
    if (!b.in_use || (b.surface_points == 0 && !b.count_due)) continue;
    cache.trim();
    forEachSurfaceVoxel(b, neighboursOf(b, &cache), emit);
  }
  for (const auto& [key, stored] : stored_.blocks()) {
    if (stored.surface_points == 0) continue;
    cache.trim();
    if (const Block* b = readStored(key, unpack(key), cache))
      forEachSurfaceVoxel(*b, neighboursOf(*b, &cache), emit);
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
