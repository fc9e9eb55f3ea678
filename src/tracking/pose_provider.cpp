#include "rgbdmap/tracking/pose_provider.hpp"

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/tracking/dense_tracker.hpp"
#include "rgbdmap/tracking/rgbd_odometry.hpp"

namespace rgbdmap {

Keys poseKeys(PoseOptions& o) {
  return {
      choice("pose.source", &o.source, {"auto", "groundtruth", "odometry", "trajectory"},
             "where camera poses come from (auto: ground truth when the source has it, else "
             "odometry)"),
      text("pose.trajectory", &o.trajectory, "TUM trajectory file when pose.source=trajectory"),
      number("pose.max_gap", &o.max_gap, 0, 10,
             "a frame farther than this (s) from any pose sample gets no pose and is not mapped"),
  };
}

bool tracksKeyframes(const PoseOptions& pose, const TrackingOptions& tracking) {
  return pose.source == "odometry" && tracking.method == "dense";
}

std::unique_ptr<PoseProvider> makePoseProvider(const PoseOptions& pose,
                                               const TrackingOptions& tracking,
                                               const CameraIntrinsics& camera, double min_depth,
                                               double max_depth, KeyframeSink* sink) {
  if (pose.source == "trajectory") {
    if (pose.trajectory.empty())
      throw InputError("pose.source=trajectory needs pose.trajectory=FILE");
    return std::make_unique<TrajectoryPoses>(pose.trajectory, pose.max_gap);
  }
  if (pose.source == "odometry") {
    if (tracking.method == "dense") {
      if (tracking.finest_level > tracking.coarsest_level)
        throw InputError("tracking.finest_level (" + std::to_string(tracking.finest_level) +
                         ") must not exceed tracking.coarsest_level (" +
                         std::to_string(tracking.coarsest_level) + ")");
      return std::make_unique<DenseTracker>(camera, tracking, static_cast<float>(min_depth),
                                            static_cast<float>(max_depth), sink);
    }
    RgbdOdometryPoses::Options options;
    options.icp = tracking.method == "opencv_rgbd_icp";
    options.min_depth = min_depth;
    options.max_depth = max_depth;
    return std::make_unique<RgbdOdometryPoses>(camera, options);
  }
  return std::make_unique<SourcePoses>();
}

}  // namespace rgbdmap
