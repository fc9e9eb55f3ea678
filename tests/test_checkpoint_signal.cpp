// Checkpoints and signals: SIGUSR1 writes a complete map while mapping goes on, SIGINT stops
// with a final save, and no signal ever leaves a partial file at the destination.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <thread>

#include "rgbdmap/runtime/checkpoint_writer.hpp"
#include "rgbdmap/runtime/run_signals.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::kRpy;

std::vector<std::string> replayArgs(const std::string& dir, const std::string& rate) {
  return {test::binary(),
          "--source",
          "tum:" + test::tumDir(kRpy),
          "--out",
          dir + "/map.pcd",
          "--rate",
          rate,
          "--no-render",
          "--stats",
          dir + "/stats.json",
          "--set",
          "checkpoint.every_keyframes=0",
          "--set",
          "checkpoint.every_seconds=0"};
}

bool waitFor(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  return test::waitUntil(condition, std::chrono::duration<double>(timeout).count());
}

// No file of the output folder is a temporary one: neither a write's "<file>.tmp-<pid>" nor a
// trajectory's loop-closure spool "<file>.anchored".
void expectNoTemporaryFile(const std::string& dir) {
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << entry.path();
    EXPECT_EQ(name.find(".anchored"), std::string::npos) << entry.path();
  }
}

// Points of each "checkpoint: N points written" line of a log, in order.
std::vector<std::size_t> checkpointPoints(const std::string& log) {
  std::vector<std::size_t> points;
  const std::string key = "checkpoint: ";
  for (auto at = log.find(key); at != std::string::npos; at = log.find(key, at + 1))
    points.push_back(std::stoul(log.substr(at + key.size())));
  return points;
}

TEST(CheckpointSignal, Sigusr1WritesCompleteMapWhileMapping) {
  const std::string dir = test::freshDir();
  // Half speed: 100 frames take ~6.6 s, long enough to observe a checkpoint mid-run.
  test::Process p(replayArgs(dir, "0.5"), dir + "/log.txt");
  ASSERT_GT(p.pid(), 0);
  ASSERT_TRUE(waitFor(
      [&] { return test::readFile(dir + "/log.txt").find("poses:") != std::string::npos; }, 60s));
  // Ask for checkpoints until one holds a real map (the first keyframe may take a while on a
  // loaded machine); each answer is a complete map on disk.
  std::size_t asked = 0;
  ASSERT_TRUE(waitFor(
      [&] {
        const std::vector<std::size_t> points = checkpointPoints(test::readFile(dir + "/log.txt"));
        if (!points.empty() && points.back() > 1000) return true;
        if (points.size() == asked) {
          p.signal(SIGUSR1);
          ++asked;
        }
        return false;
      },
      60s))
      << test::readFile(dir + "/log.txt");
  const bool still_running = p.running();
  MapCloud checkpoint;
  ASSERT_EQ(pcl::io::loadPCDFile(dir + "/map.pcd", checkpoint), 0);
  EXPECT_GT(checkpoint.size(), 1000u);
  EXPECT_EQ(checkpoint.size(), static_cast<std::size_t>(checkpoint.width) * checkpoint.height);
  EXPECT_TRUE(still_running) << "the checkpoint should come while mapping goes on";
  EXPECT_EQ(p.wait(), 0) << test::readFile(dir + "/log.txt");
  const MapCloud final_map = test::loadMap(dir + "/map.pcd");
  // The final map keeps what the checkpoint had, but for the few noisy points later views of the
  // TSDF carve away.
  EXPECT_GE(static_cast<double>(final_map.size()), 0.99 * static_cast<double>(checkpoint.size()));
  const std::string log = test::readFile(dir + "/log.txt");
  EXPECT_NE(log.find("SIGUSR1: writing a checkpoint"), std::string::npos);
  // Every write is logged as a checkpoint: the SIGUSR1 ones and the final save.
  EXPECT_NE(
      test::readFile(dir + "/stats.json")
          .find("\"checkpoints_written\": " + std::to_string(checkpointPoints(log).size()) + ","),
      std::string::npos)
      << test::readFile(dir + "/stats.json") << log;
}

TEST(CheckpointSignal, SigintStopsDrainsAndSaves) {
  const std::string dir = test::freshDir();
  // A checkpoint after every keyframe tells when mapping is under way.
  std::vector<std::string> args = replayArgs(dir, "1");
  args.insert(args.end(),
              {"--set", "checkpoint.every_keyframes=1", "--set", "checkpoint.min_seconds=0"});
  test::Process p(args, dir + "/log.txt");
  ASSERT_TRUE(waitFor(
      [&] {
        const std::vector<std::size_t> points = checkpointPoints(test::readFile(dir + "/log.txt"));
        return !points.empty() && points.back() > 1000;
      },
      60s))
      << test::readFile(dir + "/log.txt");
  p.signal(SIGINT);
  EXPECT_EQ(p.wait(), 0) << test::readFile(dir + "/log.txt");
  const MapCloud map = test::loadMap(dir + "/map.pcd");
  EXPECT_GT(map.size(), 1000u);
  const std::string stats = test::readFile(dir + "/stats.json");
  // Stopped early: fewer than all 100 frames were read, and every frame read was processed.
  const auto value = [&](const std::string& key) {
    return std::stol(stats.substr(stats.find("\"" + key + "\": ") + key.size() + 4));
  };
  EXPECT_LT(value("frames_captured"), 100);
  EXPECT_EQ(value("frames_processed"), value("frames_captured") - value("frames_dropped"));
  EXPECT_TRUE(fs::exists(dir + "/map_keyframes.txt"));
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

// Whether a process blocks SIGINT, SIGTERM and SIGUSR1 (its SigBlk mask in /proc).
bool blocksStopAndSnapshotSignals(int pid) {
  const std::string status = test::readFile("/proc/" + std::to_string(pid) + "/status");
  const auto at = status.find("SigBlk:");
  if (at == std::string::npos) return false;
  const unsigned long long mask = std::stoull(status.substr(at + 7), nullptr, 16);
  const auto bit = [](int sig) { return 1ull << (sig - 1); };
  const unsigned long long wanted = bit(SIGINT) | bit(SIGTERM) | bit(SIGUSR1);
  return (mask & wanted) == wanted;
}

// Signals from the first instant: a supervisor may ask for a snapshot or a stop before the
// program has even finished loading its libraries (0.1-0.5 s). Neither may kill it. The one
// window no program can close is before its own first instruction; the test waits until the
// launcher has run it (the process blocks the signals: microseconds after exec, on a busy
// machine maybe a few ms) and then signals at once, still deep in start-up.
TEST(CheckpointSignal, Sigusr1AtStartIsHarmless) {
  const std::string dir = test::freshDir();
  test::Process p(replayArgs(dir, "max"), dir + "/log.txt");
  ASSERT_GT(p.pid(), 0);
  ASSERT_TRUE(waitFor([&] { return blocksStopAndSnapshotSignals(p.pid()); }, 10s));
  p.signal(SIGUSR1);
  EXPECT_EQ(p.wait(), 0) << test::readFile(dir + "/log.txt");
  EXPECT_GT(test::loadMap(dir + "/map.pcd").size(), 100000u);
}

TEST(CheckpointSignal, SigintAtStartExitsCleanly) {
  const std::string dir = test::freshDir();
  test::Process p(replayArgs(dir, "max"), dir + "/log.txt");
  ASSERT_GT(p.pid(), 0);
  ASSERT_TRUE(waitFor([&] { return blocksStopAndSnapshotSignals(p.pid()); }, 10s));
  p.signal(SIGINT);
  const int code = p.wait();
  const std::string log = test::readFile(dir + "/log.txt");
  EXPECT_EQ(code, 0) << log;
  // Start-up takes 0.1-0.5 s, so the signal comes during it, unless this test itself was kept
  // off the CPU that long (a loaded machine): then it is an ordinary stop with a final save.
  if (log.find("SIGINT: stopping") == std::string::npos) {
    EXPECT_NE(log.find("SIGINT during start-up: stopping before mapping begins"), std::string::npos)
        << log;
    EXPECT_FALSE(fs::exists(dir + "/map.pcd")) << "nothing was mapped, nothing is written";
  } else {
    test::loadMap(dir + "/map.pcd");
  }
}

TEST(CheckpointSignal, PeriodicCheckpointsByKeyframeCount) {
  const std::string dir = test::freshDir();
  std::string output;
  const int code = test::run(
      test::binary() + " --source tum:" + test::tumDir(kRpy) + " --out " + dir +
          "/map.pcd --rate max -q --no-render --stats " + dir +
          "/stats.json --set checkpoint.every_keyframes=3 --set checkpoint.every_seconds=0"
          " --set checkpoint.min_seconds=0",
      &output);
  ASSERT_EQ(code, 0) << output;
  // 10 keyframes: checkpoints after keyframes 3, 6 and 9, then the final save. The writer keeps
  // only the newest pending snapshot, so a fast replay may merge some: between 2 and 4.
  const std::string stats = test::readFile(dir + "/stats.json");
  const long written = std::stol(stats.substr(stats.find("\"checkpoints_written\": ") + 23));
  EXPECT_GE(written, 2);
  EXPECT_LE(written, 4);
}

// Mapping under way at a tenth of the recorded pace (the 100 frames take 33 s at the least, so
// the run is still reading frames when a test stops it, however fast the machine), with a
// checkpoint after every keyframe: returns once one holds a real map.
bool slowReplayMapping(const std::string& log_path) {
  return waitFor(
      [&] {
        const std::vector<std::size_t> points = checkpointPoints(test::readFile(log_path));
        return !points.empty() && points.back() > 1000;
      },
      120s);
}

std::vector<std::string> slowReplayArgs(const std::string& dir) {
  std::vector<std::string> args = replayArgs(dir, "0.1");
  args.insert(args.end(),
              {"--set", "checkpoint.every_keyframes=1", "--set", "checkpoint.min_seconds=0"});
  return args;
}

// A run stopped early by one interrupt: the final save (a complete map), the statistics, the
// frames read before the stop all mapped, and no temporary file.
void expectStoppedWithTheFinalSave(const std::string& dir, const std::string& log) {
  EXPECT_EQ(test::countOccurrences(log, "SIGINT: stopping"), 1u) << log;
  EXPECT_EQ(log.find("second interrupt"), std::string::npos) << log;
  EXPECT_GT(test::loadMap(dir + "/map.pcd").size(), 1000u);
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_LT(test::jsonNumber(stats, "frames_captured"), 100) << stats;
  EXPECT_EQ(test::jsonNumber(stats, "frames_processed"),
            test::jsonNumber(stats, "frames_captured") - test::jsonNumber(stats, "frames_dropped"))
      << stats;
  expectNoTemporaryFile(dir);
}

// Two interrupts 5 ms apart are one, as a supervisor's signal to the process and to its process
// group is (RunSignals::kSameInterrupt): the run stops with the final save.
TEST(CheckpointSignal, TwoInterruptsTogetherAreOne) {
  const std::string dir = test::freshDir();
  test::Process p(slowReplayArgs(dir), dir + "/log.txt");
  ASSERT_TRUE(slowReplayMapping(dir + "/log.txt")) << test::readFile(dir + "/log.txt");
  p.signal(SIGINT);
  std::this_thread::sleep_for(5ms);
  p.signal(SIGINT);
  EXPECT_EQ(p.wait(), 0) << test::readFile(dir + "/log.txt");
  expectStoppedWithTheFinalSave(dir, test::readFile(dir + "/log.txt"));
}

// The program a command names, found on PATH as a shell finds it ("" when it is not there).
std::string onPath(const std::string& command) {
  std::string path;
  if (test::run("command -v " + command, &path) != 0) return "";
  while (!path.empty() && (path.back() == '\n' || path.back() == ' ')) path.pop_back();
  return path;
}

// `timeout -s INT T rgbdmap ...` bounds a run from a script. Without --foreground, timeout sends
// the signal to rgbdmap and then to its own process group, rgbdmap in it: one interrupt that may
// arrive twice, microseconds apart. It stops the run with the final save, as one Ctrl-C does.
// The test makes timeout's time be up once mapping is under way, by sending it the SIGALRM its
// timer would send (timeout handles both alike), so the interrupt comes mid-run on any machine.
TEST(CheckpointSignal, TimeoutSigintStopsWithTheFinalSave) {
  const std::string timeout = onPath("timeout");
  ASSERT_FALSE(timeout.empty()) << "GNU timeout (coreutils) is not on PATH";
  const std::string dir = test::freshDir();
  std::vector<std::string> args = slowReplayArgs(dir);
  // --preserve-status: timeout exits with rgbdmap's code (else 124 when its time was up).
  args.insert(args.begin(), {timeout, "--preserve-status", "-s", "INT", "3600"});
  test::Process p(args, dir + "/log.txt");
  ASSERT_TRUE(slowReplayMapping(dir + "/log.txt")) << test::readFile(dir + "/log.txt");
  p.signal(SIGALRM);
  EXPECT_EQ(p.wait(), 0) << test::readFile(dir + "/log.txt");
  expectStoppedWithTheFinalSave(dir, test::readFile(dir + "/log.txt"));
}

// A second Ctrl-C while the final save is being written, a second after the first, quits at once
// (exit 130) and leaves no temporary file of any output: map, mesh, trajectories and their
// spools. The mesh, written last, is held mid-write (StalledWrite), so the second interrupt finds
// the run writing however loaded the machine is.
TEST(CheckpointSignal, SecondSigintWhileWritingLeavesNoTemporaryFile) {
  const std::string dir = test::freshDir();
  // Slow enough that the replay cannot end before the test has seen a checkpoint; odometry, so
  // that loop closure spools the trajectories.
  std::vector<std::string> args = replayArgs(dir, "0.25");
  args.insert(args.end(), {"--mesh", dir + "/mesh.ply", "--set", "pose.source=odometry"});
  test::Process p(args, dir + "/log.txt");
  ASSERT_GT(p.pid(), 0);
  const auto log = [&] { return test::readFile(dir + "/log.txt"); };
  ASSERT_TRUE(waitFor([&] { return log().find("loop closure: on") != std::string::npos; }, 120s))
      << log();
  // A checkpoint of a real map (one at a time, as in Sigusr1WritesCompleteMapWhileMapping): then
  // every output and both spools are on disk, and the mesh is larger than the stalled pipe.
  std::size_t asked = 0;
  ASSERT_TRUE(waitFor(
      [&] {
        const std::vector<std::size_t> points = checkpointPoints(log());
        if (!points.empty() && points.back() > 1000) return true;
        if (points.size() == asked) {
          p.signal(SIGUSR1);
          ++asked;
        }
        return false;
      },
      120s))
      << log();
  for (const char* spool : {"/map_keyframes.txt.anchored", "/map_trajectory.txt.anchored"})
    ASSERT_TRUE(fs::exists(dir + spool)) << spool;

  test::StalledWrite mesh(dir + "/mesh.ply.tmp-" + std::to_string(p.pid()));
  p.signal(SIGINT);
  ASSERT_TRUE(waitFor([&] { return log().find("SIGINT: stopping") != std::string::npos; }, 120s))
      << log();
  ASSERT_TRUE(waitFor([&] { return mesh.begun(); }, 120s)) << log();
  // Twice the window after the first was taken (its line was logged): a person's second Ctrl-C,
  // not one interrupt delivered twice, whatever the machine's speed.
  std::this_thread::sleep_for(2 * RunSignals::kSameInterrupt);
  ASSERT_TRUE(p.running());
  p.signal(SIGINT);
  EXPECT_EQ(p.wait(), 130) << log();
  EXPECT_NE(log().find("second interrupt: quitting without the final save"), std::string::npos)
      << log();
  expectNoTemporaryFile(dir);
  // What was renamed into place is complete: the final map (written before the mesh) and the
  // checkpoint's mesh.
  EXPECT_GT(test::loadMap(dir + "/map.pcd").size(), 1000u);
  EXPECT_TRUE(fs::exists(dir + "/mesh.ply"));
}

}  // namespace
}  // namespace rgbdmap
