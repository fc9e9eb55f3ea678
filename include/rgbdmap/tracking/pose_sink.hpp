#pragma once

#include <Eigen/Geometry>
#include <cstdint>

namespace rgbdmap {

// Whoever keeps the poses of a trajectory as they are made: in memory (AnchoredTrajectory) or
// streamed to a file (the pipeline's TrajectoryStream). `anchor` is the tracking keyframe the
// pose was estimated against (-1: none), so that a loop closed later can still move it.
class PoseSink {
 public:
  virtual ~PoseSink() = default;
  virtual void record(double timestamp, const Eigen::Isometry3d& pose, std::int64_t anchor) = 0;
};

}  // namespace rgbdmap
