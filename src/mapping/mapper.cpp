#include "rgbdmap/mapping/mapper.hpp"

#include <spdlog/spdlog.h>

#include <chrono>

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

}  // namespace

Mapper::Mapper(const CameraIntrinsics& camera, const FilterOptions& filter, const MapOptions& map,
               const RefusionOptions& refusion, RunStats& stats, const PoseCorrections* corrections,
               PoseSink* keyframe_trajectory)
    : integrator_(camera, filter, map, WorkerPool::resolve(map.fusion_threads)),
      voxel_size_(map.voxel_size),
      min_observations_(static_cast<std::uint32_t>(map.min_observations)),
      refusion_(refusion),
      corrections_(corrections),
      map_(voxel_size_, min_observations_),
      store_(static_cast<std::size_t>(refusion.keyframe_memory * 1024.0 * 1024.0)),
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
}

void Mapper::fuse(const Frame& keyframe) {
  const Eigen::Isometry3d pose =
      corrections_ ? corrected(corrections_->snapshot(), keyframe.anchor, keyframe.pose)
                   : keyframe.pose;
  if (free_space_) free_space_->carve(keyframe.depth, camera_, pose);
  if (!corrections_) {
    integrate(keyframe, pose, map_);
  } else {
    // While a pass runs the keyframe waits for it in the store (fused once, at the pass's poses).
    if (!refusing()) integrate(keyframe, pose, map_);
    for (const std::size_t i : store_.add(keyframe, pose)) {
      // Let go to stay within budget: a pass under way moves on without it.
      if (refusing() && i < refused_at_.size())
        refused_at_.erase(refused_at_.begin() + static_cast<std::ptrdiff_t>(i));
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

bool Mapper::refine(int keyframes) {
  if (!corrections_) return false;
  if (!refusing()) {
    // Joining a saved map takes in keyframes that are not in the TSDF at all: a pass in any case.
    const PoseCorrections::Snapshot latest = corrections_->snapshot();
    if (!joinSaved(latest) && !lagsCorrections(latest)) return false;
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
  }
  const auto start = std::chrono::steady_clock::now();
  // Each kept keyframe at the newest corrections: a loop closed meanwhile is taken in by the
  // rest of this pass, and the next pass (lagsCorrections) catches what it moved before.
  const PoseCorrections::Snapshot correction = corrections_->snapshot();
  for (int k = 0; k < keyframes && refused_at_.size() < store_.size(); ++k) {
    store_.decode(refused_at_.size(), decoded_);
    const Eigen::Isometry3d pose = corrected(correction, decoded_.anchor, decoded_.pose);
    integrate(decoded_, pose, map_);
    refused_at_.push_back(pose);
    stats_.keyframes_refused.fetch_add(1);
  }
  if (refused_at_.size() == store_.size()) {
    // Caught up: the map is every kept keyframe at its corrected pose (those in memory and those
    // on disk; the ones let go saw what a kept one sees), and is shown again.
    shown_.reset();
    shown_mesh_.reset();
    map_.releaseUnused();
    for (std::size_t i = 0; i < refused_at_.size(); ++i) store_[i].fused_at = refused_at_[i];
    stats_.map_refusions.fetch_add(1);
    next_count_ = {};
  }
  stats_.refuse_latency.record(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return true;
}

void Mapper::settle() {
  if (!corrections_) return;
  const std::size_t pending = store_.size() - (refusing() ? refused_at_.size() : 0);
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
         (shown_ ? shown_->capacity() * sizeof(PackedMapPoint) : 0) +
         (shown_mesh_ ? shown_mesh_->memoryBytes() : 0) +
         (free_space_ ? free_space_->memoryBytes() : 0);
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
