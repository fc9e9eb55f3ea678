#pragma once

#include <algorithm>
#include <chrono>

namespace rgbdmap::openni2 {

// When to try reopening a camera that went away: at once, then after `first`, doubling up to
// `longest`. A camera that stays away for long costs a handful of attempts (each one enumerates
// the USB bus and logs), not one every few hundred milliseconds; one that comes back is found
// within `longest`. Reset once frames flow again, not on a mere reopen: a camera that opens but
// delivers nothing keeps backing off.
class ReconnectBackoff {
 public:
  using Clock = std::chrono::steady_clock;

  ReconnectBackoff(Clock::duration first, Clock::duration longest)
      : first_(first), longest_(longest), delay_(first) {}

  bool due(Clock::time_point now) const { return now >= next_; }
  Clock::time_point next() const { return next_; }
  Clock::duration delay() const { return delay_; }
  int attempts() const { return attempts_; }  // since the last reset

  // An attempt at `now` failed: the next one waits the current delay, which then doubles.
  void failed(Clock::time_point now) {
    ++attempts_;
    next_ = now + delay_;
    delay_ = std::min<Clock::duration>(delay_ * 2, longest_);
  }
  void succeeded() { ++attempts_; }
  void reset() {
    delay_ = first_;
    next_ = Clock::time_point{};
    attempts_ = 0;
  }

 private:
  const Clock::duration first_;
  const Clock::duration longest_;
  Clock::duration delay_;
  Clock::time_point next_{};
  int attempts_ = 0;
};

}  // namespace rgbdmap::openni2
