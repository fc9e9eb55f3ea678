// The loop thread inside the running pipeline, short enough for ThreadSanitizer: tracking hands
// keyframes over, the graph publishes corrections while fusion re-fuses the map and snapshots it
// for checkpoints, and the final map and trajectories take the last corrections. (Accuracy on
// longer sequences: test_loop_mapping.cpp.)
#include <gtest/gtest.h>

#include <filesystem>

#include "test_support.hpp"

namespace rgbdmap {
namespace {

// 1.3 circles of the default room at 10 fps, a circle in 10 s: loops from the 100th frame on.
const std::string kShortOrbit = " --frames 130 --fps 10 --loop-seconds 10";

TEST(PipelineLoopThread, ClosesLoopsWhileCheckpointingAndFinishesWithTheCorrections) {
  const std::string sequence = test::sharedSynthetic("short_orbit", kShortOrbit);
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
  // Measured (release): 16 loops, ATE 0.12 cm.
  EXPECT_GE(test::jsonNumber(stats, "loops_accepted"), 1) << log;
  EXPECT_GE(test::jsonNumber(stats, "map_refusions"), 1) << stats;
  EXPECT_EQ(test::jsonNumber(stats, "frames_processed"), 130);
  EXPECT_GT(test::jsonNumber(stats, "checkpoints_written"), 3);
  EXPECT_NE(log.find("loop closed: keyframe"), std::string::npos) << log;
  EXPECT_FALSE(test::loadMap(dir + "/map.pcd").empty());

  std::string output;
  ASSERT_EQ(test::run(test::binary() + " evaluate trajectory --estimate " + dir +
                          "/map_trajectory.txt --groundtruth " + sequence +
                          "/groundtruth.txt --json " + dir + "/ate.json",
                      &output),
            0)
      << output;
  EXPECT_LT(test::jsonNumber(test::readFile(dir + "/ate.json"), "ate_rmse_m"), 0.005);
}

}  // namespace
}  // namespace rgbdmap
