#include "rgbdmap/tracking/pose_provider.hpp"

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/tracking/dense_tracker.hpp"
#include "rgbdmap/tracking/rgbd_odometry.hpp"

namespace rgbdmap {

bool tracksKeyframes(const Config& config) {
  return config.pose_source == "odometry" && config.tracking.method == "dense";
}

std::unique_ptr<PoseProvider> makePoseProvider(const Config& config, KeyframeSink* sink) {
  if (config.pose_source == "trajectory") {
    if (config.pose_trajectory.empty())
      throw InputError("pose.source=trajectory needs pose.trajectory=FILE");
    return std::make_unique<TrajectoryPoses>(config.pose_trajectory, config.pose_max_gap);
  }
  if (config.pose_source == "odometry") {
    const TrackingOptions& tracking = config.tracking;
    if (tracking.method == "dense") {
      if (tracking.finest_level > tracking.coarsest_level)
        throw InputError("tracking.finest_level (" + std::to_string(tracking.finest_level) +
                         ") must not exceed tracking.coarsest_level (" +
                         std::to_string(tracking.coarsest_level) + ")");
      return std::make_unique<DenseTracker>(config.camera, tracking,
                                            static_cast<float>(config.min_depth),
                                            static_cast<float>(config.max_depth), sink);
    }
    RgbdOdometryPoses::Options options;
    options.icp = tracking.method == "opencv_rgbd_icp";
    options.min_depth = config.min_depth;
    options.max_depth = config.max_depth;
    return std::make_unique<RgbdOdometryPoses>(config.camera, options);
  }
  return std::make_unique<SourcePoses>();
}

}  // namespace rgbdmap
