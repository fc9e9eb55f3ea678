// `rgbdmap merge` on real frames: two sequences of one desk joined in the first one's frame, a
// session of another place said and left out, and what is refused. The synthetic room's case is
// in test_sessions_room.cpp.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "session_runs.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

using test::kRpy;
using test::kXyz;

TEST(SessionMerge, TwoSequencesOfOneDeskJoinAndASyntheticRoomIsLeftOut) {
  const std::string dir = test::freshDir();
  const std::string rpy_map = test::sharedMap(kRpy, test::tumDir(kRpy));
  const std::string xyz_map = test::sharedMap(kXyz, test::tumDir(kXyz));
  const std::string room_map =
      test::sharedMap("orbit_40", test::sharedSynthetic("orbit_40", " --frames 40"));
  const std::vector<std::string> sessions = {rpy_map + ".session", room_map + ".session",
                                             xyz_map + ".session"};
  const test::MergeRun merge = test::mergeSessions(sessions, dir + "/merged.pcd");
  test::expectAllButOneJoined(merge, sessions, 1);
  ASSERT_TRUE(merge.transforms[2]) << merge.log;
  const Eigen::Isometry3d xyz = *merge.transforms[2];

  // Both sequences' motion capture shares one frame: fr1/xyz's keyframes moved by the transform
  // merge found score with fr1/rpy's in one alignment as well as fr1/rpy's alone.
  std::vector<StampedPose> moved;
  const Trajectory xyz_keyframes = Trajectory::load(xyz_map + "_keyframes.txt");
  for (StampedPose p : xyz_keyframes.poses()) {
    p.pose = xyz * p.pose;
    moved.push_back(p);
  }
  const Trajectory rpy = Trajectory::load(rpy_map + "_keyframes.txt");
  const Trajectory rpy_truth = Trajectory::load(test::tumDir(kRpy) + "/groundtruth.txt");
  const double alone = absoluteTrajectoryError(rpy, rpy_truth).translation.rmse;
  const double together =
      absoluteTrajectoryError(
          test::merged(rpy, Trajectory(moved)),
          test::merged(rpy_truth, Trajectory::load(test::tumDir(kXyz) + "/groundtruth.txt")))
          .translation.rmse;
  std::cout << "fr1/rpy and fr1/xyz merged: ATE " << together * 100
            << " cm in one alignment (fr1/rpy alone " << alone * 100 << " cm)\n";
  EXPECT_LT(together, alone + 0.005);
  EXPECT_LT(together, 0.035);

  // The merged map has both runs' keyframes.
  EXPECT_GT(test::loadMap(dir + "/merged.pcd").size(), test::loadMap(rpy_map + ".pcd").size());

  // One trajectory beside the merged map, at the merged graph's poses: the graph's keyframes and
  // every frame both runs tracked (the room's left out), scored in one alignment.
  const Trajectory truth =
      test::merged(rpy_truth, Trajectory::load(test::tumDir(kXyz) + "/groundtruth.txt"));
  const Trajectory keyframes = Trajectory::load(dir + "/merged_keyframes.txt");
  const Trajectory frames = Trajectory::load(dir + "/merged_trajectory.txt");
  EXPECT_EQ(frames.size(), Trajectory::load(rpy_map + "_trajectory.txt").size() +
                               Trajectory::load(xyz_map + "_trajectory.txt").size());
  EXPECT_EQ(keyframes.size(), readSession(rpy_map + ".session").graph.keyframes.size() +
                                  readSession(xyz_map + ".session").graph.keyframes.size());
  const double graph = absoluteTrajectoryError(keyframes, truth).translation.rmse;
  const double every_frame = absoluteTrajectoryError(frames, truth).translation.rmse;
  std::cout << "the merged graph's " << keyframes.size() << " keyframes: ATE " << graph * 100
            << " cm; its " << frames.size() << " frames: " << every_frame * 100 << " cm\n";
  EXPECT_LT(graph, 0.035);
  EXPECT_LT(every_frame, 0.035);
}

TEST(SessionMerge, OneSessionOrABrokenOneIsRefused) {
  const std::string dir = test::freshDir();
  const std::string c = test::sharedMap(kXyz, test::tumDir(kXyz));
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " merge " + c + ".session --out " + dir + "/m.pcd", &output),
            2);
  EXPECT_NE(output.find("give two sessions or more"), std::string::npos) << output;
  EXPECT_EQ(test::run(test::binary() + " merge " + c + ".session " + dir +
                          "/missing.session --out " + dir + "/m.pcd",
                      &output),
            2);
  EXPECT_NE(output.find(dir + "/missing.session"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir + "/m.pcd"));
}

}  // namespace
}  // namespace rgbdmap
