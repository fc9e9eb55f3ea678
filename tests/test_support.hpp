#pragma once

#include <functional>
#include <string>
#include <vector>

#include "rgbdmap/runtime/checkpoint_writer.hpp"

namespace rgbdmap::test {

// The real sequences of ../shared/data/tum that most tests read.
inline const std::string kXyz = "rgbd_dataset_freiburg1_xyz";
inline const std::string kRpy = "rgbd_dataset_freiburg1_rpy_head100";

// ../shared/data (the real TUM frames and the .oni recording).
std::string dataDir();
std::string tumDir(const std::string& name);  // dataDir()/tum/<name>
// The rgbdmap executable under test.
std::string binary();
// A fresh empty folder for one test: <build>/tests/tmp/<suite>.<test>.
// Removed when the test passes (kept if it fails, and all kept with RGBDMAP_TEST_KEEP_DIRS=1).
std::string freshDir();
// A fresh empty folder for what one test process computes once and its tests share:
// <build>/tests/tmp/<name>.<pid> (CTest runs each test in a process of its own, in parallel),
// removed when the process exits with every test passed.
std::string processDir(const std::string& name);

// Runs a command with /bin/sh; returns the exit code (or 128+signal), stdout+stderr in output.
int run(const std::string& command, std::string* output = nullptr);

// Loads a PCD map; fails the current test if it cannot.
MapCloud loadMap(const std::string& path);

}  // namespace rgbdmap::test

namespace rgbdmap::test {

// A child process started with posix_spawn (stdout+stderr to `log_path`), for tests that send
// signals to a running rgbdmap.
class Process {
 public:
  Process(const std::vector<std::string>& argv, const std::string& log_path);
  ~Process();  // kills the child if it is still running
  int pid() const { return pid_; }
  void signal(int sig) const;
  // Exit code (or 128 + signal); waits at most timeout_s, then kills and returns -1.
  int wait(double timeout_s = 120.0);
  bool running();

 private:
  int pid_ = -1;
  int status_ = -1;
  bool reaped_ = false;
};

// How many times `needle` occurs in `text` (log lines of a kind).
std::size_t countOccurrences(const std::string& text, const std::string& needle);

std::string readFile(const std::string& path);
// Polls `condition` until it holds (true) or `timeout_s` has passed (false): tests wait for
// what they need to see, never for a fixed time.
bool waitUntil(const std::function<bool()>& condition, double timeout_s = 120.0);
// A number from flat JSON ("key": value, as --stats and `evaluate --json` write); a test failure
// and NaN when the key is missing.
double jsonNumber(const std::string& json, const std::string& key);
// `folder`, written once by `write` (given a private folder, renamed into place when `write`
// returns without a fatal failure) and shared by every test and process that asks for it.
std::string writeOnce(const std::string& folder,
                      const std::function<void(const std::string&)>& write);
// Where what the tests write once and share goes: <build>/tests/tmp/synthetic, or
// $RGBDMAP_TEST_SYNTHETIC_DIR (scripts/test.sh points the sanitizer runs at the release run's).
std::string sharedDir();
// A `rgbdmap synth` sequence written once into sharedDir()/<name> and shared by the tests (and
// processes) that ask for it by the same name and options.
std::string sharedSynthetic(const std::string& name, const std::string& synth_options);
// Copies a TUM folder's lists and links its image folders, so a test can corrupt the copy.
std::string copySequence(const std::string& source, const std::string& target);
// A copy of a TUM-layout sequence holding only its frames from `first` on (the lists cut, the
// ground truth whole, the image folders linked).
std::string sequenceTail(const std::string& source, std::size_t first, const std::string& target);
// The same with frames first..end-1 only.
std::string sequenceSlice(const std::string& source, std::size_t first, std::size_t end,
                          const std::string& target);

// A write that cannot finish, as on a stalled disk: a FIFO at the name a writer will write (a
// temporary file's), read by nobody. The writer's open succeeds at once (this object holds the
// reading end) and its writes block once they fill the pipe (one page), so the writing process
// stays in the middle of that file for as long as a test needs.
class StalledWrite {
 public:
  explicit StalledWrite(const std::string& path);
  ~StalledWrite();
  StalledWrite(const StalledWrite&) = delete;
  StalledWrite& operator=(const StalledWrite&) = delete;
  // Whether the writer has begun writing the file.
  bool begun() const;

 private:
  int fd_ = -1;
};

}  // namespace rgbdmap::test
