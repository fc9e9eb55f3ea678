#pragma once

#include <cstdint>
#include <vector>

#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"
#include "rgbdmap/tracking/pose_sink.hpp"

namespace rgbdmap {

// Poses as tracking gave them, each with the keyframe it was tracked against, so that they can be
// written with the pose graph's latest corrections (a loop closed later moves them too).
class AnchoredTrajectory : public PoseSink {
 public:
  // Room for `reserve` poses up front, so appending does not allocate in a run of that length.
  explicit AnchoredTrajectory(std::size_t reserve = 0);
  void push_back(double timestamp, const Eigen::Isometry3d& pose, std::int64_t anchor);
  void record(double timestamp, const Eigen::Isometry3d& pose, std::int64_t anchor) override {
    push_back(timestamp, pose, anchor);
  }
  std::size_t size() const { return poses_.size(); }
  // The poses corrected by `corrections` (as tracked when there are none).
  Trajectory resolve(const PoseCorrections* corrections) const;

 private:
  // 112 bytes a frame instead of 144: a patrol keeps every frame's pose for as long as it runs.
  struct Entry {
    double timestamp = 0.0;
    std::int64_t anchor = -1;
    Eigen::Matrix<double, 3, 4> pose;  // the top rows of the rigid motion
  };
  std::vector<Entry> poses_;
};

}  // namespace rgbdmap
