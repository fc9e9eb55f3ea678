#include "rgbdmap/runtime/run_signals.hpp"

#include <pthread.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>

#include "rgbdmap/base/thread_name.hpp"

namespace rgbdmap {
namespace {

sigset_t runSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGUSR1);
  return set;
}

}  // namespace

void RunSignals::block() {
  const sigset_t set = runSignals();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  // A file-size limit (ulimit -f) must fail the write with EFBIG, reported like a full disk,
  // instead of killing the process.
  std::signal(SIGXFSZ, SIG_IGN);
}

void RunSignals::unblock() {
  const sigset_t set = runSignals();
  pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
}

RunSignals::RunSignals(RunControl& control) : control_(control) {
  block();  // the signal thread inherits the mask: it takes the signals only through sigwait
  thread_ = std::thread([this] { wait(); });
}

RunSignals::~RunSignals() {
  done_.store(true);
  pthread_kill(thread_.native_handle(), SIGUSR1);  // wakes it now rather than at its timeout
  thread_.join();
}

bool RunSignals::runStarts(Run run) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (control_.stop.load()) return false;
  run_ = std::move(run);
  started_ = true;
  return true;
}

void RunSignals::wait() {
  nameThisThread("rgbdmap-signals");
  const sigset_t set = runSignals();
  const timespec timeout{0, 100 * 1000 * 1000};
  while (!done_.load()) {
    const int sig = sigtimedwait(&set, nullptr, &timeout);
    if (done_.load()) break;
    if (sig > 0) handle(sig);
  }
}

void RunSignals::handle(int sig) {
  const auto now = std::chrono::steady_clock::now();  // before the lock: when the signal came
  std::lock_guard<std::mutex> lock(mutex_);
  if (sig == SIGUSR1) {
    if (!started_) {
      spdlog::info("SIGUSR1 during start-up: nothing mapped yet, no checkpoint");
    } else if (run_.checkpoints) {
      spdlog::info("SIGUSR1: writing a checkpoint");
      control_.snapshot.store(true);
    } else {
      spdlog::info("SIGUSR1: ignored, this run writes as it goes and has no checkpoint");
    }
    return;
  }
  const char* name = sig == SIGINT ? "SIGINT" : "SIGTERM";
  if (first_stop_ && now - *first_stop_ <= kSameInterrupt) {
    const std::chrono::duration<double, std::milli> after = now - *first_stop_;
    spdlog::info("{} again {:.1f} ms after the first: the same interrupt, delivered twice", name,
                 after.count());
    return;
  }
  if (!first_stop_) first_stop_ = now;
  if (control_.stop.exchange(true) && sig == SIGINT) {
    // The writers may be in the middle of a temporary file: none is left behind, and the
    // destinations keep their last complete write.
    if (started_)
      for (const std::string& file : run_.temporary_files) std::remove(file.c_str());
    std::fprintf(stderr, "\nsecond interrupt: %s\n", run_.quitting.c_str());
    std::_Exit(130);
  }
  if (started_)
    spdlog::info("{}: {}", name, run_.stopping);
  else
    spdlog::info("{} during start-up: stopping before mapping begins", name);
}

}  // namespace rgbdmap
