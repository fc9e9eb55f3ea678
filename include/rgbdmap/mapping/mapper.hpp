#pragma once

#include <memory>

#include "rgbdmap/base/config.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/mapping/keyframe_integrator.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// The map half of mapping, independent of threads and sources: keyframes (with their poses, from
// FrameTracker) are fused into the map in the order given, and remembered as the keyframe
// trajectory. Owned and driven by the fusion thread.
class Mapper {
 public:
  Mapper(const Config& config, RunStats& stats);

  void fuse(const Frame& keyframe);

  // A copy of the map as a point cloud (what a checkpoint writes).
  std::shared_ptr<MapCloud> snapshot() const;
  const VoxelMap& map() const { return map_; }
  const Trajectory& keyframeTrajectory() const { return keyframes_; }

 private:
  KeyframeIntegrator integrator_;
  VoxelMap map_;
  Trajectory keyframes_;
  RunStats& stats_;
};

}  // namespace rgbdmap
