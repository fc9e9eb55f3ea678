#pragma once

#include <time.h>

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

// CPU seconds the calling thread has run: what a piece of work cost, whatever else the machine
// was doing meanwhile.
inline double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace rgbdmap
