#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/depth_registration.hpp"
#include "rgbdmap/capture/frame_source.hpp"
#include "rgbdmap/runtime/frame_queue.hpp"
#include "rgbdmap/runtime/run_thread.hpp"

namespace rgbdmap {

struct RunControl;

// Reads the source into the frame queue on its own thread, so that decoding overlaps tracking and
// fusion and a live camera is never kept waiting. Frames are numbered in the order read and
// stamped with the time they were queued (Frame::captured_at). A camera that stops delivering is
// waited for, after asking for a checkpoint (RunControl::snapshot) when frames came since the last
// outage. The queue is closed when the source ends, a stop is requested or reading fails.
class CaptureThread {
 public:
  using ErrorHandler = std::function<void(const std::string&)>;

  // Starts the thread. `on_error` is called once, from the thread, with what made it stop.
  // `registration`, if any, moves each frame's depth into the colour camera before it is queued.
  CaptureThread(FrameSource& source, FrameQueue& queue, RunStats& stats, RunControl& control,
                ErrorHandler on_error, DepthRegistration* registration = nullptr);
  void join() { thread_.join(); }

 private:
  void run();
  void read();
  // A camera that stopped delivering frames: checkpoint, then wait until it is back or a stop.
  void waitForCamera();

  FrameSource& source_;
  FrameQueue& queue_;
  RunStats& stats_;
  RunControl& control_;
  ErrorHandler on_error_;
  DepthRegistration* registration_;
  std::uint64_t index_ = 0;                       // the next frame's number
  std::uint64_t index_at_outage_checkpoint_ = 0;  // index_ when the last outage checkpointed
  RunThread thread_;                              // last: started once the members above are ready
};

}  // namespace rgbdmap
