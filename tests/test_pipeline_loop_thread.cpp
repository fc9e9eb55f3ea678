// The loop thread inside the running pipeline, short enough for ThreadSanitizer: tracking hands
// keyframes over, the graph publishes corrections while fusion re-fuses the map and snapshots it
// for checkpoints, and the final map and trajectories take the last corrections. (Accuracy on
// longer sequences: test_loop_mapping.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <tuple>
#include <vector>

#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

std::vector<std::tuple<float, float, float, std::uint32_t>> sortedPoints(const MapCloud& map) {
  std::vector<std::tuple<float, float, float, std::uint32_t>> points;
  for (const auto& p : map.points) points.emplace_back(p.x, p.y, p.z, p.rgba);
  std::sort(points.begin(), points.end());
  return points;
}

// 1.2 circles of the default room at 5 fps, a circle in 10 s: loops from the 50th frame on, every
// frame a keyframe. (130 frames at 10 fps took twice the time under ThreadSanitizer, 154 s of CPU,
// for the same loops.)
const std::string kShortOrbit = " --frames 60 --fps 5 --loop-seconds 10";

TEST(PipelineLoopThread, ClosesLoopsWhileCheckpointingAndFinishesWithTheCorrections) {
  const std::string sequence = test::sharedSynthetic("orbit_60_at_5fps", kShortOrbit);
  const std::string dir = test::freshDir();
  std::string log;
  // A checkpoint every 5 keyframes: snapshots while corrections change and the map follows them.
  ASSERT_EQ(
      test::run(test::binary() + " --source tum:" + sequence + " --out " + dir +
                    "/map.pcd --rate max -q --no-render --set pose.source=odometry"
                    " --set checkpoint.every_keyframes=5 --set checkpoint.min_seconds=0 --stats " +
                    dir + "/stats.json",
                &log),
      0)
      << log;
  const std::string stats = test::readFile(dir + "/stats.json");
  // Measured (release): 8 loops, ATE 0.07 cm.
  EXPECT_GE(test::jsonNumber(stats, "loops_accepted"), 1) << log;
  EXPECT_GE(test::jsonNumber(stats, "map_refusions"), 1) << stats;
  EXPECT_EQ(test::jsonNumber(stats, "frames_processed"), 60);
  EXPECT_GT(test::jsonNumber(stats, "checkpoints_written"), 3);
  EXPECT_NE(log.find("loop closed: keyframe"), std::string::npos) << log;
  const MapCloud map = test::loadMap(dir + "/map.pcd");
  EXPECT_FALSE(map.empty());

  // The checkpoints wrote what changed to the map store, and the final save the rest: it holds
  // the final map.
  std::string exported;
  ASSERT_EQ(test::run(test::binary() + " export " + dir + "/map.store -o " + dir + "/exported.pcd",
                      &exported),
            0)
      << exported;
  EXPECT_EQ(sortedPoints(test::loadMap(dir + "/exported.pcd")), sortedPoints(map));
  // Each kept keyframe's images and each place went into the sessions once: each session linked
  // the files of the one before and added what was new.
  double new_mb = 0;
  std::size_t sessions = 0;
  for (std::size_t at = log.find("MB of new images and places"); at != std::string::npos;
       at = log.find("MB of new images and places", at + 1)) {
    new_mb += std::stod(log.substr(log.rfind('(', at) + 1));
    ++sessions;
  }
  EXPECT_GE(sessions, 3u) << log;
  const double files_mb = static_cast<double>(fs::file_size(dir + "/map.session/images.bin") +
                                              fs::file_size(dir + "/map.session/places.data")) /
                          (1024.0 * 1024.0);
  EXPECT_NEAR(new_mb, files_mb, 0.05 * static_cast<double>(sessions) + 0.01) << log;

  std::string output;
  ASSERT_EQ(test::run(test::binary() + " evaluate trajectory --estimate " + dir +
                          "/map_trajectory.txt --groundtruth " + sequence +
                          "/groundtruth.txt --json " + dir + "/ate.json",
                      &output),
            0)
      << output;
  EXPECT_LT(test::jsonNumber(test::readFile(dir + "/ate.json"), "ate_rmse_m"), 0.005);
}

// The local window and the loops move the newest keyframes at every keyframe, and tracking does
// not wait for the loop thread: each keyframe is fused at the corrections as they were once the
// loop thread had taken in the keyframes before it, however far that thread had got meanwhile.
TEST(PipelineLoopThread, TwoLosslessReplaysWithLoopsGiveTheSameMap) {
  const std::string sequence = test::sharedSynthetic("orbit_60_at_5fps", kShortOrbit);
  const std::string dir = test::freshDir();
  std::string maps[2], trajectories[2];
  for (int i = 0; i < 2; ++i) {
    const std::string out = dir + "/run" + std::to_string(i);
    fs::create_directories(out);
    std::string log;
    ASSERT_EQ(test::run(test::binary() + " --source tum:" + sequence + " --out " + out +
                            "/map.pcd --rate max -q --no-render --set pose.source=odometry"
                            " --stats " +
                            out + "/stats.json",
                        &log),
              0)
        << log;
    EXPECT_GE(test::jsonNumber(test::readFile(out + "/stats.json"), "loops_accepted"), 1) << log;
    maps[i] = test::readFile(out + "/map.pcd");
    trajectories[i] = test::readFile(out + "/map_trajectory.txt");
  }
  EXPECT_FALSE(maps[0].empty());
  EXPECT_EQ(maps[0], maps[1]);
  EXPECT_EQ(trajectories[0], trajectories[1]);
}

}  // namespace
}  // namespace rgbdmap
