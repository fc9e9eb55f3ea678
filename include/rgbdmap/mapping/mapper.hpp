#pragma once

#include <chrono>
#include <memory>
#include <vector>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/mapping/keyframe_integrator.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/map_options.hpp"
#include "rgbdmap/mapping/surface_cloud.hpp"
#include "rgbdmap/mapping/triangle_mesh.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"
#include "rgbdmap/tracking/anchored_trajectory.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {

// The map half of mapping, independent of threads and sources: keyframes (with their poses, from
// FrameTracker) are fused into the map in the order given, and remembered as the keyframe
// trajectory. Owned and driven by the fusion thread.
//
// Without loop closure the map is one TSDF in the world frame. With it (`corrections` given),
// keyframes are fused, at their odometry poses, into a submap anchored to the tracking keyframe
// of its first keyframe; a full submap is reduced to its surface points and a new one starts.
// The map written is every submap moved by its anchor's latest correction and merged voxel by
// voxel: when a loop closes, whole submaps move with the graph and nothing is fused again.
class Mapper {
 public:
  // `keyframe_trajectory` (may be null: then the Mapper keeps it, see keyframeTrajectory()) is
  // given each fused keyframe's pose as tracked, with its anchor.
  // `map.fusion_threads` 0 is every core (WorkerPool::resolve).
  Mapper(const CameraIntrinsics& camera, const FilterOptions& filter, const MapOptions& map,
         const SubmapOptions& submaps, RunStats& stats,
         const PoseCorrections* corrections = nullptr, PoseSink* keyframe_trajectory = nullptr);

  void fuse(const Frame& keyframe);

  // A copy of the map as a point cloud (what a checkpoint writes).
  std::shared_ptr<MapCloud> snapshot() const;
  // The fused keyframes' poses, corrected by the latest loop closures (empty when they went to a
  // sink of the caller's).
  Trajectory keyframeTrajectory() const { return keyframes_.resolve(corrections_); }
  std::size_t submaps() const { return closed_.size() + 1; }

  // Keeps what meshSnapshot() needs: with loop closure, each submap is meshed when it closes
  // (its TSDF is let go then) and its mesh kept. Call before the first fuse(); a run that writes
  // no mesh does not pay for them.
  void keepMeshes() { keep_meshes_ = true; }
  // The map as a triangle mesh (marching cubes on the TSDF, see extractMesh()). With loop closure:
  // each submap's mesh moved by its anchor's latest correction and joined by MeshMerger (newest
  // first, where submaps overlap the newer one's triangles are kept).
  std::shared_ptr<TriangleMesh> meshSnapshot() const;
  std::size_t meshMemoryBytes() const { return closed_mesh_bytes_; }  // the closed submaps'
  // The TSDF's blocks and index, and the closed submaps' points.
  std::size_t memoryBytes() const;

 private:
  struct Submap {
    std::int64_t anchor = -1;
    SurfaceCloud points;  // in the odometry frame
    TriangleMesh mesh;    // likewise (only with keepMeshes())
  };
  bool startsSubmap(const Frame& keyframe) const;
  void closeSubmap();

  KeyframeIntegrator integrator_;
  double voxel_size_;
  std::uint32_t min_observations_;
  SubmapOptions submaps_;
  const PoseCorrections* corrections_;
  VoxelMap map_;  // the active submap (the whole map without loop closure)
  std::int64_t active_anchor_ = -1;
  Eigen::Isometry3d active_start_ = Eigen::Isometry3d::Identity();
  int active_keyframes_ = 0;
  std::vector<Submap> closed_;
  std::size_t closed_points_ = 0;
  bool keep_meshes_ = false;
  std::size_t closed_mesh_bytes_ = 0;
  AnchoredTrajectory keyframes_;
  PoseSink* keyframe_sink_;  // keyframes_ or the caller's
  RunStats& stats_;
  std::chrono::steady_clock::time_point next_count_{};  // when the point count is refreshed
};

}  // namespace rgbdmap
