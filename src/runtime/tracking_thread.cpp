#include "rgbdmap/runtime/tracking_thread.hpp"

#include <chrono>
#include <exception>

#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/base/thread_name.hpp"
#include "rgbdmap/runtime/run_mode.hpp"

namespace rgbdmap {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

TrackingThread::TrackingThread(Parts parts, bool wait_for_fusion, CheckpointOptions policy,
                               Checkpoint checkpoint, RunStats& stats, RunControl& control,
                               ErrorHandler on_error)
    : parts_(parts),
      wait_for_fusion_(wait_for_fusion),
      policy_(policy),
      checkpoint_(std::move(checkpoint)),
      stats_(stats),
      control_(control),
      on_error_(std::move(on_error)),
      last_checkpoint_(steadySeconds()),
      thread_(control) {
  thread_.start([this] { run(); });
}

void TrackingThread::run() {
  nameThisThread("rgbdmap-track");
  bool finished = false;
  while (!finished) {
    // Frames may stop coming (camera unplugged), so wake up regularly for checkpoints.
    if (Frame* frame = parts_.queue.pop(std::chrono::milliseconds(100), finished)) {
      const auto track_start = Clock::now();
      stats_.queue_latency.record(steadySeconds() - frame->captured_at);
      track(*frame);
      parts_.queue.release(frame);
      stats_.frames_processed.fetch_add(1);
      stats_.track_latency.record(secondsSince(track_start));
    }
    // Also while no frame comes (a camera paused, a bag played to its end): the subscriber
    // still gets the map with the last keyframes in it.
    if (parts_.publication.mapDue(stats_)) {
      MapPublication& publication = parts_.publication;
      parts_.fusion.request(MapRequest::kViewer,
                            [&publication](const Mapper& m) { publication.publishMap(m); });
    }
    const std::uint64_t keyframes = parts_.tracker.keyframesAccepted();
    const bool asked = control_.snapshot.exchange(false);
    if (asked || checkpointDue(keyframes)) {
      checkpoint_(asked);
      keyframes_at_checkpoint_ = keyframes;
      last_checkpoint_ = steadySeconds();
    }
  }
  // A snapshot request that came while the queue was draining is served by the final save.
  control_.snapshot.store(false);
  done_.store(true);
}

void TrackingThread::track(Frame& frame) {
  try {
    bool keyframe = false;
    if (parts_.tracker.track(frame)) {
      FusionThread::Settled at;
      if (parts_.settled_corrections) at = parts_.settled_corrections();
      keyframe = parts_.fusion.submit(frame, wait_for_fusion_, std::move(at));
      if (keyframe) {
        parts_.publication.afterKeyframe(frame);
        parts_.tracker.acceptKeyframe(frame);
      } else
        stats_.keyframes_deferred.fetch_add(1, std::memory_order_relaxed);
    }
    if (parts_.before_placement && frame.has_pose) parts_.before_placement->add(frame.anchor);
    // The viewer is shown the pose after loop closures, like the written trajectory.
    if (parts_.viewer_corrections)
      frame.pose = parts_.viewer_corrections->snapshot().apply(frame.anchor, frame.pose);
    parts_.publication.afterFrame(frame, parts_.tracker.state(), stats_, keyframe);
  } catch (const std::exception& e) {
    if (on_error_) on_error_(std::string(frame.origin) + ": " + e.what());
  }
}

bool TrackingThread::checkpointDue(std::uint64_t keyframes) const {
  const bool by_count =
      policy_.every_keyframes > 0 &&
      keyframes - keyframes_at_checkpoint_ >= static_cast<std::uint64_t>(policy_.every_keyframes) &&
      steadySeconds() - last_checkpoint_ >= policy_.min_seconds;
  const bool by_time = policy_.every_seconds > 0 &&
                       steadySeconds() - last_checkpoint_ >= policy_.every_seconds &&
                       keyframes > keyframes_at_checkpoint_;
  return by_count || by_time;
}

}  // namespace rgbdmap
