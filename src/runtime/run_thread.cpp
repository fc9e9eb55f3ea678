#include "rgbdmap/runtime/run_thread.hpp"

namespace rgbdmap {

RunThread::~RunThread() {
  if (thread_.joinable()) control_.stop.store(true);
  join();
}

}  // namespace rgbdmap
