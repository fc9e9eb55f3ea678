#pragma once

#include <chrono>

namespace rgbdmap {

// Seconds on the steady clock: what latencies are measured with, and the clock of
// Frame::captured_at (set by the capture thread, read against it by the tracking thread).
inline double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Seconds elapsed since `start`.
inline double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace rgbdmap
