#pragma once

#include <atomic>
#include <chrono>
#include <functional>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/runtime/frame_queue.hpp"

namespace rgbdmap {

// The run's progress on stderr (frames read, dropped and skipped, rate, keyframes, map points,
// queue, loops, tracking lost): redrawn in place on a terminal, logged every 5 s otherwise, or
// not shown (`enabled` false). Run on the thread that waits for the others.
class StatusLine {
 public:
  using Clock = std::chrono::steady_clock;

  // `start`: when the run started (the frame rate's time base).
  StatusLine(RunStats& stats, const FrameQueue& queue, bool enabled, Clock::time_point start);

  // Until `done`: keeps the stats' queue depth current, says once (whether shown or not) that a
  // stop drains the queue, and shows the line.
  void showUntil(const std::function<bool()>& done, const std::atomic<bool>& stop);
  // The line with the final counts, on a terminal (logged runs end with their summary).
  void showFinal(double wall_seconds) const;

 private:
  RunStats& stats_;
  const FrameQueue& queue_;
  bool enabled_;
  bool tty_;
  Clock::time_point start_;
};

}  // namespace rgbdmap
