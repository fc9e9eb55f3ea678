#include "rgbdmap/tracking/pose_provider.hpp"

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/tracking/rgbd_odometry.hpp"

namespace rgbdmap {

std::unique_ptr<PoseProvider> makePoseProvider(const Config& config) {
  if (config.pose_source == "trajectory") {
    if (config.pose_trajectory.empty())
      throw InputError("pose.source=trajectory needs pose.trajectory=FILE");
    return std::make_unique<TrajectoryPoses>(config.pose_trajectory, config.pose_max_gap);
  }
  if (config.pose_source == "odometry") {
    RgbdOdometryPoses::Options options;
    options.min_depth = config.min_depth;
    options.max_depth = config.max_depth;
    return std::make_unique<RgbdOdometryPoses>(config.camera, options);
  }
  return std::make_unique<SourcePoses>();
}

}  // namespace rgbdmap
