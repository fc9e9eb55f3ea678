#pragma once

#include <chrono>
#include <memory>
#include <vector>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/mapping/free_space_map.hpp"
#include "rgbdmap/mapping/ground_frame.hpp"
#include "rgbdmap/mapping/keyframe_footprint.hpp"
#include "rgbdmap/mapping/keyframe_integrator.hpp"
#include "rgbdmap/mapping/keyframe_store.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/map_options.hpp"
#include "rgbdmap/mapping/triangle_mesh.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"
#include "rgbdmap/tracking/anchored_trajectory.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {

// The map half of mapping, independent of threads and sources: keyframes (with their poses, from
// FrameTracker) are fused into the map in the order given, and remembered as the keyframe
// trajectory. Owned and driven by the fusion thread.
//
// The map is one TSDF in the world frame. With loop closure (`corrections` given) each keyframe
// is fused at its pose as corrected at that moment, and its images are kept (KeyframeStore).
// When a loop moves kept keyframes by more than refusion_shift, the map is fused again from the
// kept keyframes at their corrected poses, a few keyframes at a time between new ones (refine()).
// So the map written is what fusing the keyframes at the poses known then gives: one surface per
// wall, not one per visit. A pass is one of two kinds:
// - a region pass, when the keyframes that see what the loop moved are at most
//   refusion.region_share of those kept: the cells the moved keyframes see, before and after the
//   move (KeyframeFootprint), are fused again from those keyframes into a TSDF of their own,
//   which then replaces the map's blocks in those cells. The map stays as it is meanwhile (and
//   new keyframes are fused into it, and into the region's when they see it). Its work grows with
//   what the loop moved, not with the map;
// - a whole pass otherwise (a loop that moved most of the map, or a saved map joined): what is
//   shown and written is the map as it was when the pass began, kept as its point cloud (and
//   mesh): the TSDF it came from is emptied and the pass fuses into its memory, so a pass never
//   holds two TSDFs of the whole map (nor hands 100 MB back to the system to fault it in again),
//   and keyframes that arrive meanwhile are fused once, by the pass.
class Mapper {
 public:
  // `keyframe_trajectory` (may be null: then the Mapper keeps it, see keyframeTrajectory()) is
  // given each fused keyframe's pose as tracked, with its anchor.
  // `map.fusion_threads` 0 is every core (WorkerPool::resolve).
  Mapper(const CameraIntrinsics& camera, const FilterOptions& filter, const MapOptions& map,
         const RefusionOptions& refusion, RunStats& stats,
         const PoseCorrections* corrections = nullptr, PoseSink* keyframe_trajectory = nullptr);

  // Fuses a keyframe, then re-fuses up to refusion_pace kept ones if the map is following a loop.
  // `at`: the corrections to fuse and re-fuse at (a lossless replay's, taken when the keyframe
  // was handed over, so that the map does not depend on when fusion got to it); null: the
  // latest.
  void fuse(const Frame& keyframe, const PoseCorrections::Snapshot* at = nullptr);
  // Re-fuses up to `keyframes` kept keyframes if the map lags the latest corrections; returns
  // whether it did any work (so an idle caller knows to call again).
  bool refine(int keyframes);
  // Until the map is fused at the latest corrections (before the final save).
  void settle();

  // Continuing a saved session (--continue): its kept keyframes wait until the run joins the saved
  // map's frame (PoseCorrections::Snapshot::joined); then they are taken in with the run's own
  // and the map is fused again from all of them at the joined poses. Until then the map is the
  // run's own, in its own frame (what is written if it never joins).
  void continueFrom(std::vector<KeyframeStore::Entry> saved);
  // Whether the run has yet to join the saved map it continues (then the map is the run's own).
  bool awaitingJoin() const { return awaiting_join_; }

  // Whether meshes are asked for (meshSnapshot()): a pass then keeps the mesh it began from too.
  void keepMeshes(bool keep) { keep_meshes_ = keep; }
  // Whether an OctoMap is asked for: keyframes then also carve the free space they see through
  // (FreeSpaceMap), at the resolution given.
  void keepFreeSpace(const OctomapOptions& options) {
    free_space_ = std::make_unique<FreeSpaceMap>(options);
  }

  // The map as a point cloud (what a checkpoint writes): one extracted now, or while a pass runs
  // the one it began from (kept packed, unpacked for each call).
  std::shared_ptr<const MapCloud> snapshot() const;
  // The map as a triangle mesh (marching cubes on the TSDF, see extractMesh()); while a pass runs,
  // the one it began from (when keepMeshes(), else the pass's own so far).
  std::shared_ptr<const TriangleMesh> meshSnapshot() const;
  // The fused keyframes' poses, corrected by the latest loop closures (empty when they went to a
  // sink of the caller's).
  Trajectory keyframeTrajectory() const { return keyframes_.resolve(corrections_); }
  // A copy of the free space seen so far (null unless keepFreeSpace()).
  std::shared_ptr<const FreeSpaceMap> freeSpaceSnapshot() const {
    return free_space_ ? std::make_shared<const FreeSpaceMap>(*free_space_) : nullptr;
  }
  // What the keyframes fused so far say about which way is up (GroundFrame).
  const UpEvidence& upEvidence() const { return up_; }
  // The kept keyframes (loop closure only).
  const KeyframeStore& keptKeyframes() const { return store_; }
  // The TSDF's blocks and index, the kept keyframes' images, and while a pass runs the map it
  // began from.
  std::size_t memoryBytes() const;
  // The TSDF's blocks on disk (beyond map.memory), and the bytes of their scratch files.
  std::size_t blocksOnDisk() const;
  std::uint64_t mapDiskBytes() const;

 private:
  Eigen::Isometry3d corrected(const PoseCorrections::Snapshot& correction, std::int64_t anchor,
                              const Eigen::Isometry3d& pose) const;
  // Whether a kept keyframe's corrected pose (by `correction`, the latest) has moved by
  // refusion_shift from where it was fused.
  bool lagsCorrections(const PoseCorrections::Snapshot& correction);
  // The corrections fuse() was given, else the latest.
  PoseCorrections::Snapshot latestCorrections() const {
    return pinned_ ? *pinned_ : corrections_->snapshot();
  }
  // Takes in the saved keyframes once the run has joined their frame; returns whether it did.
  bool joinSaved(const PoseCorrections::Snapshot& correction);
  bool refusing() const { return shown_ != nullptr; }
  // Starts a region pass if the keyframes to fuse again are few enough; returns whether it did.
  bool beginRegionPass(const PoseCorrections::Snapshot& correction);
  void beginWholePass();
  // Fuses up to `keyframes` of the region pass's into its TSDF; at the end, into the map.
  void refineRegion(int keyframes);
  // Fuses up to `keyframes` kept keyframes into the emptied map; at the end, shows it again.
  void refineWhole(int keyframes);
  // The volume of that many footprint cells (m^3, rounded).
  double regionVolume(std::size_t cells) const;
  // Where a keyframe's surfaces lie, seen from `pose`.
  KeyframeFootprint footprintOf(const Frame& keyframe, const Eigen::Isometry3d& pose) const;
  void integrate(const Frame& keyframe, const Eigen::Isometry3d& pose, VoxelMap& map);
  void noteUp(const Frame& keyframe, const Eigen::Isometry3d& pose);

  KeyframeIntegrator integrator_;
  double voxel_size_;
  std::uint32_t min_observations_;
  RefusionOptions refusion_;
  std::size_t max_blocks_;  // in memory, by map.memory (0: no limit)
  const PoseCorrections* corrections_;
  const PoseCorrections::Snapshot* pinned_ = nullptr;  // during fuse(), its `at`
  VoxelMap map_;
  KeyframeStore store_;
  // While a pass runs: the map it began from (what is shown), and the poses the first
  // refused_at_.size() kept keyframes were re-fused at (into map_).
  std::shared_ptr<const PackedMapCloud> shown_;
  std::shared_ptr<const TriangleMesh> shown_mesh_;
  bool keep_meshes_ = false;
  std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>> refused_at_;
  // A region pass under way: the cells it fuses again (sorted), the cells whose keyframes it
  // fuses (those and their neighbours), the kept keyframes' ids in store order and, for those
  // fused so far, the pose and footprint they were fused at.
  struct RegionPass {
    RegionPass(double voxel_size, std::uint32_t min_observations)
        : map(voxel_size, min_observations) {}
    std::vector<std::uint64_t> cells, reach;
    std::vector<std::uint64_t> keyframes;
    std::vector<bool> moved;  // by the loop (else only seeing what it moved)
    std::vector<std::pair<Eigen::Isometry3d, KeyframeFootprint>,
                Eigen::aligned_allocator<std::pair<Eigen::Isometry3d, KeyframeFootprint>>>
        fused;
    VoxelMap map;
  };
  std::unique_ptr<RegionPass> region_;
  std::chrono::steady_clock::time_point pass_began_;
  std::vector<KeyframeFootprint> refused_footprints_;  // whole pass: beside refused_at_
  FilterOptions filter_;
  std::uint64_t checked_version_ = 0;        // corrections compared with the kept keyframes
  std::vector<KeyframeStore::Entry> saved_;  // continuing: until the run joins their frame
  bool awaiting_join_ = false;
  Frame decoded_;  // a kept keyframe, decoded for re-fusion
  AnchoredTrajectory keyframes_;
  PoseSink* keyframe_sink_;  // keyframes_ or the caller's
  UpEvidence up_;
  CameraIntrinsics camera_;
  std::unique_ptr<FreeSpaceMap> free_space_;
  RunStats& stats_;
  std::chrono::steady_clock::time_point next_count_{};  // when the point count is refreshed
};

}  // namespace rgbdmap
