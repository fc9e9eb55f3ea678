#include "rgbdmap/runtime/frame_tracker.hpp"

#include <chrono>
#include <vector>

namespace rgbdmap {
FrameTracker::FrameTracker(KeyframeSelector selector, std::unique_ptr<PoseProvider> poses,
                           RunStats& stats, PoseSink* trajectory)
    : poses_(std::move(poses)), selector_(selector), trajectory_(trajectory), stats_(stats) {}

bool FrameTracker::track(Frame& frame) {
  const auto start = std::chrono::steady_clock::now();
  frame.anchor = -1;  // frames are reused: only a tracker that anchors them sets it
  const bool posed = poses_->estimate(frame);
  stats_.pose_latency.record(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  const TrackingState state = poses_->state();
  switch (state) {
    case TrackingState::kTracked:
      stats_.frames_tracked.fetch_add(1, std::memory_order_relaxed);
      break;
    case TrackingState::kRelocalised:
      stats_.frames_relocalised.fetch_add(1, std::memory_order_relaxed);
      break;
    case TrackingState::kLost:
      stats_.frames_lost.fetch_add(1, std::memory_order_relaxed);
      break;
    case TrackingState::kNoPose:
      break;
  }
  stats_.tracking_lost.store(state == TrackingState::kLost, std::memory_order_relaxed);
  if (trajectory_ && (posed || state == TrackingState::kLost))
    trajectory_->record(frame.timestamp, frame.pose, frame.anchor);
  if (!posed) {
    stats_.frames_without_pose.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  return selector_.wants(frame.pose);
}

void FrameTracker::acceptKeyframe(const Frame& frame) {
  selector_.accept(frame.pose);
  ++keyframes_accepted_;
}

}  // namespace rgbdmap
