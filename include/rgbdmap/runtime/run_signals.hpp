#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "rgbdmap/runtime/run_thread.hpp"

namespace rgbdmap {

// The signals of a run, taken the same way by every front door (rgbdmap, rgbdmap_node,
// rgbdmap record). They are blocked in every thread and taken by one thread of this class with
// sigwait, so no handler ever runs inside mapping, ROS or camera code:
// - SIGUSR1: a checkpoint now (RunControl::snapshot). Before the run starts there is nothing to
//   write yet: a no-op.
// - SIGINT or SIGTERM: stop (RunControl::stop). Before the run starts, it does not start and
//   writes nothing; after, it stops as the run says (mapping drains and saves).
// - A second SIGINT, more than kSameInterrupt after the first SIGINT or SIGTERM: removes the
//   temporary files the run may have on disk and quits at once (exit 130). Each destination keeps
//   its last complete write; none is half-written.
// - SIGINT or SIGTERM again within kSameInterrupt of the first: the same interrupt, delivered
//   twice. `timeout -s INT` (unless --foreground) and supervisors signal the process and then its
//   process group, the process included; taken as a second Ctrl-C, that lost the final save.
class RunSignals {
 public:
  // How long after the first stop signal another one is still the same interrupt. Delivery to a
  // process and then to its group is a few system calls in a row: microseconds apart, a few
  // milliseconds if the sender is preempted between them on a loaded machine. A person's second
  // Ctrl-C, meant to quit, comes after seeing the "stopping" line: a bare visual reaction takes
  // 0.2-0.3 s, reading and deciding longer. 0.5 s is a hundred times the slowest delivery and
  // longer than any such reaction; a quicker double press counts once, the next press quits.
  static constexpr std::chrono::milliseconds kSameInterrupt{500};

  // What a run tells the signal thread when it starts.
  struct Run {
    std::vector<std::string> temporary_files;  // removed by a second SIGINT
    bool checkpoints = true;  // false: the run writes as it goes and SIGUSR1 has nothing to do
    std::string stopping = "stopping (interrupt again to quit without saving)";
    std::string quitting = "quitting without the final save";
  };

  // Blocks the signals in the calling thread and starts the signal thread. Construct it before
  // any other thread exists, so that all inherit the mask.
  explicit RunSignals(RunControl& control);
  ~RunSignals();
  RunSignals(const RunSignals&) = delete;
  RunSignals& operator=(const RunSignals&) = delete;

  // The run starts: from here on SIGUSR1 asks it for a checkpoint and a stop ends it as `run`
  // says. False when a stop came first: then the run must not start. One lock orders this and
  // the handling of a signal, so a stop during start-up never ends in a saved map (its message
  // said none would be).
  bool runStarts(Run run);

  // SIGINT, SIGTERM and SIGUSR1 in the calling thread: blocked (before any thread exists), or
  // unblocked again (for commands that keep the default actions: Ctrl-C ends them at once).
  // block() also makes a file-size limit fail writes (EFBIG) rather than kill the process.
  static void block();
  static void unblock();

 private:
  void wait();
  void handle(int sig);

  RunControl& control_;
  std::mutex mutex_;  // orders runStarts() and the handling of a signal
  Run run_;
  bool started_ = false;
  // When the first SIGINT or SIGTERM came, on the monotonic clock (a wall-clock step must not
  // join two interrupts or split one).
  std::optional<std::chrono::steady_clock::time_point> first_stop_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

}  // namespace rgbdmap
