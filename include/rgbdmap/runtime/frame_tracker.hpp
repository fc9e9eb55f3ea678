#pragma once

#include <cstdint>
#include <memory>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/mapping/keyframe_selector.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"
#include "rgbdmap/tracking/pose_sink.hpp"

namespace rgbdmap {

// The per-frame half of mapping, run for every frame on the tracking thread: the frame's pose
// (tracked, lost or relocalised, each counted), the trajectory of every frame, and whether the
// frame should become a keyframe. Fusion is elsewhere (Mapper), so a slow keyframe never holds
// up the next frame's pose.
class FrameTracker {
 public:
  // `trajectory` (may be null) is given every frame that got a pose, in order, with its anchor; a
  // lost frame carries the pose the tracker predicted for it. Frames the source has no pose for
  // at all (a gap in the ground truth) are not given.
  // `selector` (see makeKeyframeSelector) picks the keyframes.
  FrameTracker(KeyframeSelector selector, std::unique_ptr<PoseProvider> poses, RunStats& stats,
               PoseSink* trajectory = nullptr);

  // Estimates the frame's pose and records it. Returns true when the frame should be fused; call
  // acceptKeyframe() once it has been handed over (if it could not be, the next frame is
  // proposed instead).
  bool track(Frame& frame);
  void acceptKeyframe(const Frame& frame);

  std::uint64_t keyframesAccepted() const { return keyframes_accepted_; }
  TrackingState state() const { return poses_->state(); }
  const PoseProvider& poses() const { return *poses_; }

 private:
  std::unique_ptr<PoseProvider> poses_;
  KeyframeSelector selector_;
  PoseSink* trajectory_;
  RunStats& stats_;
  std::uint64_t keyframes_accepted_ = 0;
};

}  // namespace rgbdmap
