#pragma once

#include <memory>
#include <string>

#include "rgbdmap/config.hpp"
#include "rgbdmap/frame.hpp"
#include "rgbdmap/trajectory.hpp"

namespace rgbdmap {

// Gives each frame its camera-to-world pose, or says it has none (the frame is then counted
// and not mapped).
class PoseProvider {
 public:
  virtual ~PoseProvider() = default;
  // Sets frame.pose and frame.has_pose; returns has_pose.
  virtual bool estimate(Frame& frame) = 0;
  virtual std::string describe() const = 0;
};

// The source's own poses (a dataset's ground truth, interpolated at the colour stamp).
class SourcePoses : public PoseProvider {
 public:
  bool estimate(Frame& frame) override { return frame.has_pose; }
  std::string describe() const override { return "ground truth from the source"; }
};

// Poses interpolated from a TUM trajectory file (e.g. from another SLAM system).
class TrajectoryPoses : public PoseProvider {
 public:
  TrajectoryPoses(const std::string& path, double max_gap)
      : path_(path), trajectory_(Trajectory::load(path)), max_gap_(max_gap) {}
  bool estimate(Frame& frame) override {
    const auto pose = trajectory_.interpolate(frame.timestamp, max_gap_);
    frame.has_pose = pose.has_value();
    if (pose) frame.pose = *pose;
    return frame.has_pose;
  }
  std::string describe() const override { return "trajectory file " + path_; }

 private:
  std::string path_;
  Trajectory trajectory_;
  double max_gap_;
};

// Builds the provider named by config pose.source. Odometry needs the camera intrinsics.
std::unique_ptr<PoseProvider> makePoseProvider(const Config& config);

}  // namespace rgbdmap
