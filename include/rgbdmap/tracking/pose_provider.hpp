#pragma once

#include <memory>
#include <string>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/option_keys.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/tracking/keyframe_sink.hpp"
#include "rgbdmap/tracking/tracking_options.hpp"

namespace rgbdmap {

// How the last estimate went. A tracker that loses the camera still gives the frame the pose it
// predicted (written to the per-frame trajectory), but the frame is not mapped.
enum class TrackingState {
  kNoPose,       // the source has no pose for this frame (e.g. a gap in the ground truth)
  kTracked,      // a pose good enough to map
  kLost,         // tracking failed on this frame; frame.pose is the prediction
  kRelocalised,  // tracking was lost and has just been recovered: the pose is good again
};

// Gives each frame its camera-to-world pose, or says it has none (the frame is then counted
// and not mapped).
class PoseProvider {
 public:
  virtual ~PoseProvider() = default;
  // Sets frame.pose and frame.has_pose; returns has_pose (true: map this frame).
  virtual bool estimate(Frame& frame) = 0;
  virtual std::string describe() const = 0;
  // The outcome of the last estimate().
  virtual TrackingState state() const = 0;
  // What tracking measured of the camera over the run, for the log; empty when nothing.
  virtual std::string report() const { return {}; }
};

// The source's own poses (a dataset's ground truth, interpolated at the colour stamp).
class SourcePoses : public PoseProvider {
 public:
  bool estimate(Frame& frame) override {
    state_ = frame.has_pose ? TrackingState::kTracked : TrackingState::kNoPose;
    return frame.has_pose;
  }
  std::string describe() const override { return "ground truth from the source"; }
  TrackingState state() const override { return state_; }

 private:
  TrackingState state_ = TrackingState::kNoPose;
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
    state_ = frame.has_pose ? TrackingState::kTracked : TrackingState::kNoPose;
    return frame.has_pose;
  }
  std::string describe() const override { return "trajectory file " + path_; }
  TrackingState state() const override { return state_; }

 private:
  std::string path_;
  Trajectory trajectory_;
  double max_gap_;
  TrackingState state_ = TrackingState::kNoPose;
};

// Where camera poses come from (config section "pose").
struct PoseOptions {
  std::string source = "auto";  // auto | groundtruth | odometry | trajectory
  std::string trajectory;       // TUM file for source=trajectory
  double max_gap = 0.05;        // s to the nearest ground truth or trajectory sample
};

Keys poseKeys(PoseOptions& o);

// Builds the provider named by pose.source. Odometry needs the camera intrinsics and the depth
// range used (filter.min_depth, filter.max_depth). The dense tracker hands its keyframes to
// `sink` when one is given (loop closure).
std::unique_ptr<PoseProvider> makePoseProvider(const PoseOptions& pose,
                                               const TrackingOptions& tracking,
                                               const CameraIntrinsics& camera, double min_depth,
                                               double max_depth, KeyframeSink* sink = nullptr);

// Whether makePoseProvider makes a tracker with keyframes a pose graph can be built on.
bool tracksKeyframes(const PoseOptions& pose, const TrackingOptions& tracking);

}  // namespace rgbdmap
