#include "rgbdmap/tracking/anchored_trajectory.hpp"

namespace rgbdmap {

AnchoredTrajectory::AnchoredTrajectory(std::size_t reserve) {
  poses_.reserve(reserve);
  anchors_.reserve(reserve);
}

void AnchoredTrajectory::push_back(double timestamp, const Eigen::Isometry3d& pose,
                                   std::int64_t anchor) {
  poses_.push_back({timestamp, pose});
  anchors_.push_back(anchor);
}

Trajectory AnchoredTrajectory::resolve(const PoseCorrections* corrections) const {
  if (!corrections) return Trajectory(poses_);
  const PoseCorrections::Snapshot snapshot = corrections->snapshot();
  std::vector<StampedPose> out = poses_;
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i].pose = snapshot.apply(anchors_[i], out[i].pose);
  return Trajectory(std::move(out));
}

}  // namespace rgbdmap
