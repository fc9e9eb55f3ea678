#pragma once

#include <pthread.h>

#include <string>

namespace rgbdmap {

// Names the calling thread as `top -H`, `ps -L`, gdb and perf show it: "rgbdmap-track" rather
// than a dozen "rgbdmap" when a user asks which part of the run takes a core. Linux keeps 15
// characters; a longer name is cut there rather than refused.
inline void nameThisThread(const std::string& name) {
  ::pthread_setname_np(::pthread_self(), name.substr(0, 15).c_str());
}

}  // namespace rgbdmap
