#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

namespace rgbdmap {

struct StampedPose {
  double timestamp = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera-to-world
};

// A trajectory in TUM format: "timestamp tx ty tz qx qy qz qw" (quaternion scalar-last).
class Trajectory {
 public:
  Trajectory() = default;
  explicit Trajectory(std::vector<StampedPose> poses) : poses_(std::move(poses)) {}

  // Throws InputError naming file and line for malformed lines, NaN values, non-unit
  // quaternions or timestamps that go backwards.
  static Trajectory load(const std::string& path);
  // Writes TUM format (temp file + rename); throws std::runtime_error on failure.
  void save(const std::string& path) const;

  // Pose at time t: slerp/lerp between the two neighbouring samples. No pose when t is outside
  // the trajectory or either neighbour is farther than max_gap seconds away.
  std::optional<Eigen::Isometry3d> interpolate(double t, double max_gap = 0.05) const;

  void push_back(const StampedPose& p) { poses_.push_back(p); }
  std::size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }
  const StampedPose& operator[](std::size_t i) const { return poses_[i]; }
  const std::vector<StampedPose>& poses() const { return poses_; }
  std::vector<double> timestamps() const;

 private:
  std::vector<StampedPose> poses_;
};

}  // namespace rgbdmap
