// The fusion thread in process (so ThreadSanitizer sees both sides): keyframes fused in the order
// submitted give the same map as fusing them in turn; a full set of slots refuses a live
// keyframe at once instead of blocking tracking; map tasks run on the fusion thread between
// keyframes; finish() fuses everything submitted.
#include <gtest/gtest.h>
#include <pthread.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "rgbdmap/base/thread_name.hpp"
#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/runtime/fusion_thread.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using namespace std::chrono_literals;

struct Fixture {
  Config config;
  std::vector<Frame> frames;
};

// The first `n` frames of fr1/xyz with their ground-truth poses.
Fixture loadFrames(std::size_t n) {
  Fixture f;
  const std::string folder = test::tumDir(test::kXyz);
  f.config.loadPreset(TumSequence::presetForFolder(folder));
  TumSequence sequence(folder);
  for (std::size_t i = 0; i < n; ++i) {
    Frame frame;
    std::string error;
    EXPECT_TRUE(sequence.load(i, frame, error)) << error;
    EXPECT_TRUE(frame.has_pose);
    frame.index = i;
    f.frames.push_back(frame);
  }
  return f;
}

bool waitFor(const std::atomic<bool>& flag) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!flag.load()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

// The calling thread's name as top -H and gdb show it.
std::string threadName() {
  char name[16] = {};
  pthread_getname_np(pthread_self(), name, sizeof name);
  return name;
}

void expectSameCloud(const MapCloud& a, const MapCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].getVector3fMap(), b[i].getVector3fMap()) << i;
    ASSERT_EQ(a[i].rgba, b[i].rgba) << i;
  }
}

TEST(PipelineFusion, FusedOnItsThreadGivesTheSameMapAsFusedInTurn) {
  const Fixture f = loadFrames(6);
  RunStats sequential_stats, threaded_stats;
  Mapper sequential(f.config.camera, f.config.filter, f.config.map, f.config.refusion,
                    sequential_stats);
  for (const Frame& frame : f.frames) sequential.fuse(frame);

  Mapper threaded(f.config.camera, f.config.filter, f.config.map, f.config.refusion,
                  threaded_stats);
  {
    FusionThread fusion(threaded, 2, 640, 480, nullptr);
    for (const Frame& frame : f.frames) ASSERT_TRUE(fusion.submit(frame, true));
    fusion.finish();
  }
  EXPECT_EQ(threaded_stats.keyframes.load(), 6u);
  EXPECT_EQ(threaded.keyframeTrajectory().size(), 6u);
  expectSameCloud(*sequential.snapshot(), *threaded.snapshot());
  EXPECT_GT(threaded.snapshot()->size(), 20000u);  // six fr1 frames: ~30k surface voxels
}

TEST(PipelineFusion, TheMapIsTheSameWhateverTheFusionThreads) {
  Fixture f = loadFrames(6);
  f.config.map.fusion_threads = 1;
  RunStats one_stats, three_stats;
  Mapper one(f.config.camera, f.config.filter, f.config.map, f.config.refusion, one_stats);
  f.config.map.fusion_threads = 3;  // more than the CI machine's cores: tasks interleave
  Mapper three(f.config.camera, f.config.filter, f.config.map, f.config.refusion, three_stats);
  for (const Frame& frame : f.frames) {
    one.fuse(frame);
    three.fuse(frame);
  }
  expectSameCloud(*one.snapshot(), *three.snapshot());
  EXPECT_GT(three.snapshot()->size(), 20000u);
}

TEST(WorkerPool, RunsEveryTaskOnceOnAllItsThreadsAndRethrowsTheFirstError) {
  WorkerPool pool(3);
  EXPECT_EQ(pool.threads(), 3);
  for (int round = 0; round < 50; ++round) {  // runs back to back reuse the same threads
    std::vector<std::atomic<int>> runs(997);
    auto body = [&](std::size_t i) { runs[i].fetch_add(1); };
    pool.run(runs.size(), body);
    for (std::size_t i = 0; i < runs.size(); ++i) ASSERT_EQ(runs[i].load(), 1) << i;
  }
  auto failing = [](std::size_t i) {
    if (i == 5) throw std::runtime_error("task 5 failed");
  };
  EXPECT_THROW(pool.run(100, failing), std::runtime_error);
  std::atomic<int> after{0};
  auto count = [&](std::size_t) { after.fetch_add(1); };
  pool.run(10, count);  // still usable
  EXPECT_EQ(after.load(), 10);
  EXPECT_EQ(WorkerPool::resolve(0),
            static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
}

TEST(ThreadName, ANameLongerThanLinuxKeepsIsCutAtFifteenCharacters) {
  std::string named;
  std::thread([&] {
    nameThisThread("rgbdmap-a-name-too-long");
    named = threadName();
  }).join();
  EXPECT_EQ(named, "rgbdmap-a-name-");
}

TEST(PipelineFusion, BusySlotsRefuseALiveKeyframeAtOnceAndLoseNothingAccepted) {
  const Fixture f = loadFrames(8);
  RunStats stats;
  Mapper mapper(f.config.camera, f.config.filter, f.config.map, f.config.refusion, stats);
  FusionThread fusion(mapper, 2, 640, 480, nullptr);
  // Hold the fusion thread inside a map task, as a slow keyframe would.
  std::atomic<bool> inside{false}, release{false};
  fusion.request(MapRequest::kCheckpoint, [&](const Mapper&) {
    inside.store(true);
    while (!release.load()) std::this_thread::sleep_for(1ms);
  });
  ASSERT_TRUE(waitFor(inside));
  std::size_t accepted = 0;
  for (const Frame& frame : f.frames) {
    if (!fusion.submit(frame, false)) break;  // returns at once: tracking is never held up
    ++accepted;
  }
  // Two slots plus the pool's spare frames; never all eight.
  EXPECT_GE(accepted, 2u);
  EXPECT_LT(accepted, f.frames.size());
  release.store(true);
  fusion.finish();
  EXPECT_EQ(stats.keyframes.load(), accepted);
  ASSERT_EQ(mapper.keyframeTrajectory().size(), accepted);
  for (std::size_t i = 0; i < accepted; ++i)
    EXPECT_EQ(mapper.keyframeTrajectory()[i].timestamp, f.frames[i].timestamp) << i;
}

TEST(PipelineFusion, MapTasksRunBetweenKeyframesOnTheFusionThread) {
  const Fixture f = loadFrames(4);
  RunStats stats;
  Mapper mapper(f.config.camera, f.config.filter, f.config.map, f.config.refusion, stats);
  FusionThread fusion(mapper, 4, 640, 480, nullptr);
  std::atomic<bool> done{false};
  std::size_t keyframes_seen = 99;
  std::thread::id task_thread;
  std::string task_thread_name;
  for (std::size_t i = 0; i < 2; ++i) ASSERT_TRUE(fusion.submit(f.frames[i], true));
  fusion.request(MapRequest::kCheckpoint, [&](const Mapper& m) {
    keyframes_seen = m.keyframeTrajectory().size();
    task_thread = std::this_thread::get_id();
    task_thread_name = threadName();
    done.store(true);
  });
  ASSERT_TRUE(waitFor(done));
  EXPECT_LE(keyframes_seen, 2u);
  EXPECT_NE(task_thread, std::this_thread::get_id());
  EXPECT_EQ(task_thread_name, "rgbdmap-fusion");
  for (std::size_t i = 2; i < 4; ++i) ASSERT_TRUE(fusion.submit(f.frames[i], true));
  fusion.finish();
  EXPECT_EQ(mapper.keyframeTrajectory().size(), 4u);
}

}  // namespace
}  // namespace rgbdmap
