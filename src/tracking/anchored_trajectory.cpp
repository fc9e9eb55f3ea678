#include "rgbdmap/tracking/anchored_trajectory.hpp"

namespace rgbdmap {

AnchoredTrajectory::AnchoredTrajectory(std::size_t reserve) { poses_.reserve(reserve); }

void AnchoredTrajectory::push_back(double timestamp, const Eigen::Isometry3d& pose,
                                   std::int64_t anchor) {
  poses_.push_back({timestamp, anchor, pose.matrix().topRows<3>()});
}

Trajectory AnchoredTrajectory::resolve(const PoseCorrections* corrections) const {
  const PoseCorrections::Snapshot snapshot =
      corrections ? corrections->snapshot() : PoseCorrections::Snapshot{};
  std::vector<StampedPose> out(poses_.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const Entry& e = poses_[i];
    out[i].timestamp = e.timestamp;
    out[i].pose.matrix().topRows<3>() = e.pose;
    if (corrections) out[i].pose = snapshot.apply(e.anchor, out[i].pose);
  }
  return Trajectory(std::move(out));
}

}  // namespace rgbdmap
