#include "rgbdmap/mapping/mapper.hpp"

#include <chrono>

#include "rgbdmap/mapping/mesh_extractor.hpp"
#include "rgbdmap/mapping/mesh_merger.hpp"
#include "rgbdmap/mapping/point_merger.hpp"

namespace rgbdmap {
namespace {

// The point count shown while mapping is refreshed at most this often: it is for people watching
// the status line, and counting revisits every block changed since the last count (every 10th
// keyframe cost 8% of an every-frame replay's CPU). A snapshot gives the exact count.
constexpr std::chrono::milliseconds kCountPointsEvery{1000};
// Blocks far from any surface are freed every this many keyframes, once no keyframe has updated
// them for kPruneIdleKeyframes (blocks in view are updated again and again: freeing them would
// only allocate them anew) and every voxel is at least kPruneClearanceVoxels in front of a surface.
constexpr std::uint64_t kPruneEvery = 10;
constexpr std::uint64_t kPruneIdleKeyframes = 30;
constexpr float kPruneClearanceVoxels = 2.0f;

double angle(const Eigen::Isometry3d& t) { return Eigen::AngleAxisd(t.linear()).angle(); }

}  // namespace

Mapper::Mapper(const CameraIntrinsics& camera, const FilterOptions& filter, const MapOptions& map,
               const SubmapOptions& submaps, RunStats& stats, const PoseCorrections* corrections,
               PoseSink* keyframe_trajectory)
    : integrator_(camera, filter, map, WorkerPool::resolve(map.fusion_threads)),
      voxel_size_(map.voxel_size),
      min_observations_(static_cast<std::uint32_t>(map.min_observations)),
      submaps_(submaps),
      corrections_(corrections),
      map_(voxel_size_, min_observations_),
      keyframe_sink_(keyframe_trajectory ? keyframe_trajectory : &keyframes_),
      stats_(stats) {}

bool Mapper::startsSubmap(const Frame& keyframe) const {
  if (!corrections_ || keyframe.anchor < 0) return false;
  if (active_anchor_ < 0) return true;  // the first anchored keyframe
  // Still on the tracking keyframe the submap started on: every frame since is placed relative
  // to it, and a loop closure moves them as one. Splitting here would only copy the same surface
  // into submap after submap (a camera at rest kept 10 MB more a minute).
  if (keyframe.anchor == active_anchor_) return false;
  const Eigen::Isometry3d moved = active_start_.inverse() * keyframe.pose;
  return active_keyframes_ >= submaps_.submap_keyframes ||
         moved.translation().norm() > submaps_.submap_distance ||
         angle(moved) > submaps_.submap_rotation;
}

void Mapper::closeSubmap() {
  if (active_keyframes_ > 0) {
    Submap submap;
    submap.anchor = active_anchor_;
    std::vector<VoxelMap::SurfacePoint> points;
    map_.extract(points);
    submap.points = SurfaceCloud(points);
    closed_points_ += submap.points.size();
    if (keep_meshes_) {
      submap.mesh = extractMesh(map_);
      // Kept for the whole run: without the slack push_back left.
      submap.mesh.vertices.shrink_to_fit();
      submap.mesh.colours.shrink_to_fit();
      submap.mesh.triangles.shrink_to_fit();
      closed_mesh_bytes_ += submap.mesh.memoryBytes();
    }
    closed_.push_back(std::move(submap));
  }
  map_ = VoxelMap(voxel_size_, min_observations_);  // lets the TSDF's memory go
  active_keyframes_ = 0;
}

void Mapper::fuse(const Frame& keyframe) {
  if (startsSubmap(keyframe)) {
    closeSubmap();
    active_anchor_ = keyframe.anchor;
    active_start_ = keyframe.pose;
  }
  integrator_.integrate(keyframe, map_, stats_);
  ++active_keyframes_;
  keyframe_sink_->record(keyframe.timestamp, keyframe.pose, keyframe.anchor);
  const std::uint64_t fused = stats_.keyframes.fetch_add(1) + 1;
  const auto now = std::chrono::steady_clock::now();
  if (now >= next_count_) {
    stats_.map_points.store(closed_points_ + map_.pointCount(&integrator_.pool()));
    next_count_ = now + kCountPointsEvery;
  }
  if (fused % kPruneEvery == 0)
    map_.pruneFreeSpace(kPruneIdleKeyframes,
                        kPruneClearanceVoxels * static_cast<float>(voxel_size_));
}

std::size_t Mapper::memoryBytes() const {
  std::size_t bytes = map_.memoryBytes();
  for (const Submap& submap : closed_) bytes += submap.points.memoryBytes();
  return bytes;
}

std::shared_ptr<MapCloud> Mapper::snapshot() const {
  auto cloud = std::make_shared<MapCloud>();
  if (!corrections_ || (closed_.empty() && active_anchor_ < 0)) {
    map_.extract(*cloud);
  } else {
    const PoseCorrections::Snapshot correction = corrections_->snapshot();
    PointMerger merger(voxel_size_);
    for (const Submap& submap : closed_) merger.add(submap.points, correction.of(submap.anchor));
    std::vector<VoxelMap::SurfacePoint> active;
    map_.extract(active);
    merger.add(SurfaceCloud(active), correction.of(active_anchor_));
    merger.extract(*cloud);
  }
  stats_.map_points.store(cloud->size());  // what is written
  return cloud;
}

std::shared_ptr<TriangleMesh> Mapper::meshSnapshot() const {
  if (!corrections_ || (closed_.empty() && active_anchor_ < 0))
    return std::make_shared<TriangleMesh>(extractMesh(map_));
  const PoseCorrections::Snapshot correction = corrections_->snapshot();
  MeshMerger merger(voxel_size_);
  // Newest first: the active submap, then back through the closed ones.
  merger.add(extractMesh(map_), correction.of(active_anchor_));
  for (auto submap = closed_.rbegin(); submap != closed_.rend(); ++submap)
    merger.add(submap->mesh, correction.of(submap->anchor));
  return std::make_shared<TriangleMesh>(merger.take());
}

}  // namespace rgbdmap
