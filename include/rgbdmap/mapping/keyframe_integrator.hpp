#pragma once

#include <optional>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/capture/lens_undistortion.hpp"
#include "rgbdmap/mapping/back_projector.hpp"
#include "rgbdmap/mapping/depth_filter.hpp"
#include "rgbdmap/mapping/depth_smoother.hpp"
#include "rgbdmap/mapping/map_options.hpp"
#include "rgbdmap/mapping/tsdf_integrator.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// One keyframe into the map: filter the depth image (range, flying pixels, specks), smooth it,
// optionally remove statistical outliers, undo lens distortion, fuse along the lines of sight
// into the voxel map. Buffers are kept between keyframes.
class KeyframeIntegrator {
 public:
  // `threads`: threads that fuse (the caller's included), from map.fusion_threads resolved.
  KeyframeIntegrator(const CameraIntrinsics& camera, const FilterOptions& filter,
                     const MapOptions& map, int threads = 1);
  void integrate(const Frame& frame, VoxelMap& map, RunStats& stats) {
    integrate(frame, frame.pose, map, stats);
  }
  // At `pose` instead of the frame's own (loop closure's correction of it).
  void integrate(const Frame& frame, const Eigen::Isometry3d& pose, VoxelMap& map, RunStats& stats);
  // The threads that fuse, for other work on the map between keyframes.
  WorkerPool& pool() { return pool_; }

 private:
  void removeStatisticalOutliers(const Frame& frame);

  DepthFilter filter_;
  DepthSmoother smoother_;
  TsdfIntegrator tsdf_;
  WorkerPool pool_;
  bool statistical_ = false;
  int sor_mean_k_ = 50;
  double sor_stddev_ = 1.0;
  std::optional<LensUndistortion> lens_;  // when the lens distorts and filter.undistort is set
  cv::Mat depth_, scratch_, pinhole_depth_;
  DepthSmoother::Buffers smoothing_;
  BackProjector projector_;  // for the statistical filter
  PointBatch batch_;
};

}  // namespace rgbdmap
