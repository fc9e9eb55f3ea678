#pragma once

#include <memory>

#include "rgbdmap/base/config.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/mapping/keyframe_integrator.hpp"
#include "rgbdmap/mapping/keyframe_selector.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"

namespace rgbdmap {

// The mapping algorithm for one frame, independent of threads and sources:
// pose -> keyframe? -> integrate. Owned and driven by the mapping thread.
class Mapper {
 public:
  Mapper(const Config& config, std::unique_ptr<PoseProvider> poses, RunStats& stats);

  // Returns true when the frame became a keyframe and was fused.
  bool process(Frame& frame);

  // A copy of the map as a point cloud (what a checkpoint writes).
  std::shared_ptr<MapCloud> snapshot() const;
  const VoxelMap& map() const { return map_; }
  const Trajectory& keyframeTrajectory() const { return keyframes_; }
  const PoseProvider& poses() const { return *poses_; }

 private:
  std::unique_ptr<PoseProvider> poses_;
  KeyframeSelector selector_;
  KeyframeIntegrator integrator_;
  VoxelMap map_;
  Trajectory keyframes_;
  RunStats& stats_;
  std::uint32_t min_observations_;
  std::uint64_t posed_frames_ = 0;
};

}  // namespace rgbdmap
