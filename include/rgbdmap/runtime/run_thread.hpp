#pragma once

#include <atomic>
#include <functional>
#include <thread>

namespace rgbdmap {

// Requests from outside the run (the signal thread, a service, tests). Only atomics: safe from
// anywhere.
struct RunControl {
  std::atomic<bool> stop{false};      // SIGINT/SIGTERM: stop capture, drain, final save
  std::atomic<bool> snapshot{false};  // SIGUSR1: write a checkpoint now
};

// A thread of the run, joined when it goes out of scope. One still running then (the run was
// left by an exception) is told to stop first (RunControl::stop) rather than waited for until
// its source ends.
class RunThread {
 public:
  explicit RunThread(RunControl& control) : control_(control) {}
  ~RunThread();
  RunThread(const RunThread&) = delete;
  RunThread& operator=(const RunThread&) = delete;

  void start(std::function<void()> body) { thread_ = std::thread(std::move(body)); }
  void join() {
    if (thread_.joinable()) thread_.join();
  }

 private:
  RunControl& control_;
  std::thread thread_;
};

}  // namespace rgbdmap
