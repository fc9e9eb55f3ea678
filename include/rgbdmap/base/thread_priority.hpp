#pragma once

#include <sys/resource.h>
#include <unistd.h>

namespace rgbdmap {

// How far each background thread steps back from tracking when two cores are short (Linux
// niceness, per thread). Tracking must answer every frame within its period; fusion may lag a
// few keyframes behind (its queue), loop closure and localisation more. Measured on the 30 x 20 m
// floor at the camera's rate (docs/benchmarks.md, "The local window").
constexpr int kFusionNiceness = 3;
constexpr int kLoopNiceness = 10;

// The calling thread's niceness.
inline int threadNiceness() { return ::getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid())); }

// Lowers the calling thread's priority to `niceness` (an unprivileged thread cannot raise it
// again: a lower niceness than the thread has is left alone).
inline void stepBackFromTracking(int niceness) {
  if (niceness > threadNiceness())
    ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), niceness);
}

}  // namespace rgbdmap
