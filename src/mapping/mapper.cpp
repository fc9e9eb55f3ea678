#include "rgbdmap/mapping/mapper.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/mapping/mesh_extractor.hpp"

namespace rgbdmap {
namespace {

// The point count shown while mapping is refreshed at most this often: it is for people watching
// the status line, and counting revisits every block changed since the last count (every 10th
// keyframe cost 8% of an every-frame replay's CPU). A snapshot gives the exact count.
constexpr std::chrono::milliseconds kCountPointsEvery{1000};
// Blocks away from any surface are freed every this many keyframes, once no keyframe has updated
// them for kPruneIdleKeyframes (blocks in view are updated again and again: freeing them would
// only allocate them anew) and every voxel is at least kPruneClearanceVoxels in front of a surface
// (free space) or behind one (what a wide band of a far or noisy view reached).
constexpr std::uint64_t kPruneEvery = 10;
constexpr std::uint64_t kPruneIdleKeyframes = 30;
constexpr float kPruneClearanceVoxels = 2.0f;
// Beyond map.memory, blocks go to disk once no keyframe has updated them for this many: those in
// view stay, and a camera turning back within a few keyframes finds its blocks in memory.
constexpr std::uint64_t kStoreIdleKeyframes = 10;

// Whether two sorted lists share an element.
bool intersects(const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b) {
  auto i = a.begin();
  auto j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (*i < *j)
      ++i;
    else if (*j < *i)
      ++j;
    else
      return true;
  }
  return false;
}

}  // namespace

Mapper::Mapper(const CameraIntrinsics& camera, const FilterOptions& filter, const MapOptions& map,
               const RefusionOptions& refusion, RunStats& stats, const PoseCorrections* corrections,
               PoseSink* keyframe_trajectory)
    : integrator_(camera, filter, map, WorkerPool::resolve(map.fusion_threads)),
      voxel_size_(map.voxel_size),
      min_observations_(static_cast<std::uint32_t>(map.min_observations)),
      refusion_(refusion),
      max_blocks_(static_cast<std::size_t>(map.memory * 1024.0 * 1024.0 /
                                           static_cast<double>(sizeof(VoxelMap::Block)))),
      corrections_(corrections),
      map_(voxel_size_, min_observations_),
      store_(static_cast<std::size_t>(refusion.keyframe_memory * 1024.0 * 1024.0)),
      filter_(filter),
      keyframe_sink_(keyframe_trajectory ? keyframe_trajectory : &keyframes_),
      camera_(camera),
      stats_(stats) {}

Eigen::Isometry3d Mapper::corrected(const PoseCorrections::Snapshot& correction,
                                    std::int64_t anchor, const Eigen::Isometry3d& pose) const {
  return anchor < 0 ? pose : correction.apply(anchor, pose);
}

void Mapper::integrate(const Frame& keyframe, const Eigen::Isometry3d& pose, VoxelMap& map) {
  integrator_.integrate(keyframe, pose, map, stats_);
  const std::uint64_t integrations = map.integrations();
  if (integrations % kPruneEvery == 0)
    map.pruneAwayFromSurfaces(kPruneIdleKeyframes,
                              kPruneClearanceVoxels * static_cast<float>(voxel_size_));
  const std::size_t stored = map.keepWithin(max_blocks_, kStoreIdleKeyframes);
  if (stored > 0) stats_.map_blocks_stored.fetch_add(stored);
}

void Mapper::fuse(const Frame& keyframe, const PoseCorrections::Snapshot* at) {
  pinned_ = corrections_ ? at : nullptr;
  struct Unpin {
    const PoseCorrections::Snapshot*& pinned;
    ~Unpin() { pinned = nullptr; }
  } unpin{pinned_};
  const Eigen::Isometry3d pose =
      corrections_ ? corrected(latestCorrections(), keyframe.anchor, keyframe.pose) : keyframe.pose;
  if (free_space_) free_space_->carve(keyframe.depth, camera_, pose);
  if (!corrections_) {
    integrate(keyframe, pose, map_);
  } else {
    // While a whole pass runs the keyframe waits for it in the store (fused once, at the pass's
    // poses); a region pass fuses it again if it sees the region (its blocks there are the pass's).
    if (!refusing()) integrate(keyframe, pose, map_);
    KeyframeStore::Entry entry = store_.encode(keyframe, pose);
    entry.footprint = footprintOf(keyframe, pose);
    const bool in_region = region_ && intersects(entry.footprint.cells(), region_->reach);
    for (const std::size_t i : store_.add(std::move(entry))) {
      // Let go to stay within budget: a pass under way moves on without it.
      if (refusing() && i < refused_at_.size()) {
        refused_at_.erase(refused_at_.begin() + static_cast<std::ptrdiff_t>(i));
        refused_footprints_.erase(refused_footprints_.begin() + static_cast<std::ptrdiff_t>(i));
      }
    }
    if (in_region) {
      region_->keyframes.push_back(store_[store_.size() - 1].id);
      region_->moved.push_back(false);
    }
    refine(refusion_.refusion_pace);
  }
  keyframe_sink_->record(keyframe.timestamp, keyframe.pose, keyframe.anchor);
  noteUp(keyframe, pose);
  stats_.keyframes.fetch_add(1);
  stats_.map_bytes.store(memoryBytes());
  const auto now = std::chrono::steady_clock::now();
  if (!refusing() && now >= next_count_) {
    stats_.map_points.store(map_.pointCount(&integrator_.pool()));
    next_count_ = now + kCountPointsEvery;
  }
}

void Mapper::noteUp(const Frame& keyframe, const Eigen::Isometry3d& pose) {
  // At the pose fused at: a later loop's correction turns a keyframe by a fraction of a degree
  // (but joining a saved map may turn the whole run: then joinSaved() turns what is noted).
  const Eigen::Matrix3d rotation = pose.linear();
  up_.camera_up -= rotation.col(1);
  if (keyframe.has_up) {
    up_.accelerometer_up += rotation * keyframe.up;
    ++up_.accelerometer_keyframes;
  }
  up_.cameras.push_back(pose.translation());
}

void Mapper::continueFrom(std::vector<KeyframeStore::Entry> saved) {
  saved_ = std::move(saved);
  awaiting_join_ = corrections_ != nullptr;
}

bool Mapper::joinSaved(const PoseCorrections::Snapshot& correction) {
  if (!awaiting_join_ || !correction.joined) return false;
  awaiting_join_ = false;
  // What the run noted about up, moved with it into the saved frame; the saved keyframes' cameras
  // added (the saved run's accelerometer is not kept).
  const Eigen::Isometry3d moved = correction.of(correction.first_own);
  up_.camera_up = moved.linear() * up_.camera_up;
  up_.accelerometer_up = moved.linear() * up_.accelerometer_up;
  for (Eigen::Vector3d& c : up_.cameras) c = moved * c;
  for (const KeyframeStore::Entry& e : saved_) {
    up_.camera_up -= e.fused_at.linear().col(1);
    up_.cameras.push_back(e.fused_at.translation());
  }
  for (std::size_t i = 0; i < store_.size(); ++i)
    store_[i].fused_at = corrected(correction, store_[i].anchor, store_[i].pose);
  store_.adopt(std::move(saved_));
  saved_ = {};
  spdlog::info(
      "continuing: the map is fused again from {} kept keyframes, the saved map's and "
      "this run's, at the joined poses",
      store_.size());
  return true;
}

bool Mapper::lagsCorrections(const PoseCorrections::Snapshot& correction) {
  if (correction.version == checked_version_) return false;
  checked_version_ = correction.version;
  for (std::size_t i = 0; i < store_.size(); ++i) {
    const KeyframeStore::Entry& e = store_[i];
    if (viewpointDistance(e.fused_at, corrected(correction, e.anchor, e.pose)) >
        refusion_.refusion_shift)
      return true;
  }
  return false;
}

double Mapper::regionVolume(std::size_t cells) const {
  const double edge = VoxelMap::cellSize(voxel_size_);
  return std::round(static_cast<double>(cells) * edge * edge * edge);
}

KeyframeFootprint Mapper::footprintOf(const Frame& keyframe, const Eigen::Isometry3d& pose) const {
  return KeyframeFootprint(keyframe.depth, camera_, pose, voxel_size_, filter_.min_depth,
                           filter_.max_depth);
}

bool Mapper::refine(int keyframes) {
  if (!corrections_) return false;
  if (!refusing() && !region_) {
    // Joining a saved map takes in keyframes that are not in the TSDF at all: a whole pass.
    const PoseCorrections::Snapshot latest = latestCorrections();
    const bool joined = joinSaved(latest);
    if (!joined && !lagsCorrections(latest)) return false;
    if (joined || !beginRegionPass(latest)) beginWholePass();
    pass_began_ = std::chrono::steady_clock::now();
  }
  const auto start = std::chrono::steady_clock::now();
  if (region_)
    refineRegion(keyframes);
  else
    refineWhole(keyframes);
  stats_.refuse_latency.record(secondsSince(start));
  return true;
}

bool Mapper::beginRegionPass(const PoseCorrections::Snapshot& correction) {
  if (refusion_.region_share <= 0.0) return false;
  auto pass = std::make_unique<RegionPass>(voxel_size_, min_observations_);
  std::vector<bool> moved(store_.size(), false);
  for (std::size_t i = 0; i < store_.size(); ++i) {
    const KeyframeStore::Entry& e = store_[i];
    const Eigen::Isometry3d pose = corrected(correction, e.anchor, e.pose);
    if (viewpointDistance(e.fused_at, pose) <= refusion_.refusion_shift) continue;
    moved[i] = true;
    const std::vector<std::uint64_t>& before = e.footprint.cells();
    const KeyframeFootprint after = e.footprint.moved(pose * e.fused_at.inverse(), voxel_size_);
    pass->cells.insert(pass->cells.end(), before.begin(), before.end());
    pass->cells.insert(pass->cells.end(), after.cells().begin(), after.cells().end());
  }
  KeyframeFootprint::sortUnique(pass->cells);
  pass->reach = KeyframeFootprint::dilate(pass->cells);
  for (std::size_t i = 0; i < store_.size(); ++i) {
    if (!moved[i] && !intersects(store_[i].footprint.cells(), pass->reach)) continue;
    pass->keyframes.push_back(store_[i].id);
    pass->moved.push_back(moved[i]);
  }
  if (static_cast<double>(pass->keyframes.size()) >
      refusion_.region_share * static_cast<double>(store_.size()))
    return false;
  // Its TSDF keeps the region and what borders it: the rest of what its keyframes see is
  // neither needed nor taken.
  const std::vector<std::uint64_t>* reach = &pass->reach;
  pass->map.limitTo(
      [reach](const Eigen::Vector3i& block) { return KeyframeFootprint::holds(*reach, block); });
  region_ = std::move(pass);
  return true;
}

void Mapper::refineRegion(int keyframes) {
  RegionPass& pass = *region_;
  // Each at the newest corrections, as a whole pass does.
  const PoseCorrections::Snapshot correction = latestCorrections();
  for (int k = 0; k < keyframes && pass.fused.size() < pass.keyframes.size(); ++k) {
    const std::size_t i = store_.find(pass.keyframes[pass.fused.size()]);
    if (i == store_.size()) {  // let go meanwhile
      pass.fused.emplace_back();
      continue;
    }
    store_.decode(i, decoded_);
    const Eigen::Isometry3d pose = corrected(correction, decoded_.anchor, decoded_.pose);
    integrate(decoded_, pose, pass.map);
    // (Only the moved ones take their new pose and footprint at the end.)
    pass.fused.emplace_back(
        pose, pass.moved[pass.fused.size()] ? footprintOf(decoded_, pose) : KeyframeFootprint());
    stats_.keyframes_refused.fetch_add(1);
  }
  if (pass.fused.size() < pass.keyframes.size()) return;
  // The cells the moved keyframes' surfaces are in now, exactly (beginRegionPass() moved cells'
  // centres): those next to the region are its too, since the pass fused every keyframe seeing
  // them.
  std::vector<std::uint64_t> cells = pass.cells;
  for (std::size_t k = 0; k < pass.keyframes.size(); ++k) {
    if (!pass.moved[k]) continue;
    for (const std::uint64_t c : pass.fused[k].second.cells())
      if (std::binary_search(pass.reach.begin(), pass.reach.end(), c)) cells.push_back(c);
  }
  KeyframeFootprint::sortUnique(cells);
  map_.replaceRegion(pass.map, [&](const Eigen::Vector3i& block) {
    return KeyframeFootprint::holds(cells, block);
  });
  // The moved keyframes are in the map at their new poses, whole: every cell they saw before and
  // see now was fused again. The others only where they see the region: they stay at the poses
  // they were fused at (within refusion_shift of their corrected ones).
  for (std::size_t k = 0; k < pass.keyframes.size(); ++k) {
    if (!pass.moved[k]) continue;
    const std::size_t i = store_.find(pass.keyframes[k]);
    if (i == store_.size()) continue;
    store_[i].fused_at = pass.fused[k].first;
    store_[i].footprint = std::move(pass.fused[k].second);
  }
  spdlog::info(
      "the map follows a loop: {} of {} kept keyframes fused again where it moved ({} m^3) "
      "in {:.1f} s",
      pass.keyframes.size(), store_.size(), regionVolume(cells.size()), secondsSince(pass_began_));
  region_.reset();
  stats_.region_refusions.fetch_add(1);
  stats_.map_refusions.fetch_add(1);
  next_count_ = {};
}

void Mapper::beginWholePass() {
  // The map as it is stays shown (a cloud, and a mesh when asked for: a fraction of the TSDF)
  // while the pass fuses a new one in its place. The cloud is packed (16 bytes a point): it is
  // kept to the pass's end, when the new TSDF is whole beside it.
  auto cloud = std::make_shared<PackedMapCloud>();
  map_.pointCount(&integrator_.pool());  // an exact count: the cloud is reserved to fit
  map_.extract(*cloud);
  stats_.map_points.store(cloud->size());
  if (keep_meshes_) shown_mesh_ = std::make_shared<const TriangleMesh>(extractMesh(map_));
  shown_ = std::move(cloud);
  // Emptied, not freed: the pass fuses about as many blocks again into the same memory.
  map_.clear();
  refused_at_.clear();
  refused_footprints_.clear();
}

void Mapper::refineWhole(int keyframes) {
  // Each kept keyframe at the newest corrections: a loop closed meanwhile is taken in by the
  // rest of this pass, and the next pass (lagsCorrections) catches what it moved before.
  const PoseCorrections::Snapshot correction = latestCorrections();
  for (int k = 0; k < keyframes && refused_at_.size() < store_.size(); ++k) {
    store_.decode(refused_at_.size(), decoded_);
    const Eigen::Isometry3d pose = corrected(correction, decoded_.anchor, decoded_.pose);
    integrate(decoded_, pose, map_);
    refused_at_.push_back(pose);
    refused_footprints_.push_back(footprintOf(decoded_, pose));
    stats_.keyframes_refused.fetch_add(1);
  }
  if (refused_at_.size() < store_.size()) return;
  spdlog::info("the map follows a loop: all {} kept keyframes fused again in {:.1f} s",
               store_.size(), secondsSince(pass_began_));
  // Caught up: the map is every kept keyframe at its corrected pose (those in memory and those
  // on disk; the ones let go saw what a kept one sees), and is shown again.
  shown_.reset();
  shown_mesh_.reset();
  map_.releaseUnused();
  for (std::size_t i = 0; i < refused_at_.size(); ++i) {
    store_[i].fused_at = refused_at_[i];
    store_[i].footprint = std::move(refused_footprints_[i]);
  }
  refused_footprints_.clear();
  stats_.map_refusions.fetch_add(1);
  next_count_ = {};
}

void Mapper::settle() {
  if (!corrections_) return;
  const std::size_t pending = region_ ? region_->keyframes.size() - region_->fused.size()
                                      : store_.size() - (refusing() ? refused_at_.size() : 0);
  bool logged = false;
  while (refine(16)) {
    if (!logged) {
      spdlog::info("re-fusing up to {} kept keyframes at their final poses", pending);
      logged = true;
    }
  }
}

std::size_t Mapper::memoryBytes() const {
  std::size_t saved = 0;
  for (const KeyframeStore::Entry& e : saved_) saved += e.imageBytes();
  return map_.memoryBytes() + store_.memoryBytes() + saved +
         (region_ ? region_->map.memoryBytes() : 0) +
         (shown_ ? shown_->capacity() * sizeof(PackedMapPoint) : 0) +
         (shown_mesh_ ? shown_mesh_->memoryBytes() : 0) +
         (free_space_ ? free_space_->memoryBytes() : 0);
}

std::size_t Mapper::blocksOnDisk() const {
  return map_.storedBlocks().size() + (region_ ? region_->map.storedBlocks().size() : 0);
}

std::uint64_t Mapper::mapDiskBytes() const {
  return map_.storedBlocks().fileBytes() + (region_ ? region_->map.storedBlocks().fileBytes() : 0);
}

std::shared_ptr<const MapCloud> Mapper::snapshot() const {
  if (refusing()) return std::make_shared<const MapCloud>(toMapCloud(*shown_));
  auto cloud = std::make_shared<MapCloud>();
  map_.extract(*cloud);
  stats_.map_points.store(cloud->size());  // what is written
  return cloud;
}

std::shared_ptr<const TriangleMesh> Mapper::meshSnapshot() const {
  if (shown_mesh_) return shown_mesh_;
  return std::make_shared<const TriangleMesh>(extractMesh(map_));
}

}  // namespace rgbdmap
