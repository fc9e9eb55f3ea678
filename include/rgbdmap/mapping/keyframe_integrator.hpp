#pragma once

#include "rgbdmap/base/config.hpp"
#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/mapping/back_projector.hpp"
#include "rgbdmap/mapping/depth_filter.hpp"
#include "rgbdmap/mapping/depth_smoother.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// One keyframe into the map: filter the depth image (range, flying pixels, specks), smooth it,
// back-project with the pose, optionally remove statistical outliers, fuse into the voxel map.
// Buffers are kept between keyframes.
class KeyframeIntegrator {
 public:
  explicit KeyframeIntegrator(const Config& config);
  void integrate(const Frame& frame, VoxelMap& map, RunStats& stats);

 private:
  void removeStatisticalOutliers();

  DepthFilter filter_;
  DepthSmoother smoother_;
  BackProjector projector_;
  bool statistical_ = false;
  int sor_mean_k_ = 50;
  double sor_stddev_ = 1.0;
  cv::Mat depth_, scratch_;
  cv::Mat inverse_, valid_, sum_, count_, low_, high_;  // smoother buffers
  PointBatch batch_, kept_;
};

}  // namespace rgbdmap
