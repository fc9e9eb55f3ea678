#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/config/run_options.hpp"
#include "rgbdmap/runtime/frame_queue.hpp"
#include "rgbdmap/runtime/frame_tracker.hpp"
#include "rgbdmap/runtime/fusion_thread.hpp"
#include "rgbdmap/runtime/map_publisher.hpp"
#include "rgbdmap/runtime/run_thread.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {

class FramesBeforePlacement;  // run_mode.hpp

// Takes every frame from the queue on its own thread: gives it its pose (FrameTracker), hands
// keyframes to the fusion thread, shows the viewer the frame and, when due, the map, and asks
// the fusion thread for checkpoints. Runs until the queue is closed and drained.
class TrackingThread {
 public:
  using ErrorHandler = std::function<void(const std::string&)>;
  // `asked`: by SIGUSR1 or a camera outage (then the whole map is wanted), not by the policy.
  using Checkpoint = std::function<void(bool asked)>;

  struct Parts {
    FrameQueue& queue;
    FrameTracker& tracker;
    FusionThread& fusion;
    MapPublication& publication;
    // Moves the poses the viewer is shown by the loop closures (null: shown as tracked).
    const PoseCorrections* viewer_corrections;
    // Localising or continuing: every posed frame's anchor, to count those before the saved map
    // was recognised (null: neither).
    FramesBeforePlacement* before_placement = nullptr;
    // A lossless replay with loop closure: called as a keyframe is handed to fusion, it says
    // which corrections the keyframe is to be fused at (those once the loop thread has taken in
    // every keyframe before it), for the fusion thread to fetch, and wait for, when it gets to
    // the keyframe; tracking goes on meanwhile (null: fused at the latest).
    std::function<FusionThread::Settled()> settled_corrections = nullptr;
  };

  // Starts the thread. `wait_for_fusion`: a keyframe waits for a fusion slot (a lossless replay,
  // whose map must not depend on timing) instead of being deferred to the next frame (live).
  // `policy` says when it asks for a checkpoint besides SIGUSR1 and a camera outage (after
  // `every_keyframes` new keyframes but no sooner than `min_seconds` after the previous one, or
  // every `every_seconds` while keyframes come; each 0 = off); `checkpoint` asks for one;
  // `on_error` is told of a frame that failed (the thread goes on).
  TrackingThread(Parts parts, bool wait_for_fusion, CheckpointOptions policy, Checkpoint checkpoint,
                 RunStats& stats, RunControl& control, ErrorHandler on_error);

  // Set once every frame is taken and the last checkpoint request made.
  bool done() const { return done_.load(); }
  void join() { thread_.join(); }

 private:
  void run();
  void track(Frame& frame);
  bool checkpointDue(std::uint64_t keyframes) const;

  Parts parts_;
  bool wait_for_fusion_;
  CheckpointOptions policy_;
  Checkpoint checkpoint_;
  RunStats& stats_;
  RunControl& control_;
  ErrorHandler on_error_;
  double last_checkpoint_;  // steady-clock seconds
  std::uint64_t keyframes_at_checkpoint_ = 0;
  std::atomic<bool> done_{false};
  RunThread thread_;  // last: started once the members above are ready
};

}  // namespace rgbdmap
