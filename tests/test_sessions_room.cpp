// Sessions at the scale of a room (release build only: each test maps a lap of the synthetic
// room): a second run localised in the first run's map, and two runs merged into one map.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "session_runs.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

// One lap round the 5x4 m room (seed 1), and another lap (seed 2) 15 cm further from the walls,
// of which the second half is used: it starts on the far side of the room from the first run's
// start.
const std::string kFirstWalk = " --path walk --frames 360 --seed 1";
const std::string kSecondWalk = " --path walk --frames 360 --seed 2 --path-inset 0.95";

class RoomSessions : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::freshDir();
    first_ = test::sharedSynthetic("walk_lap_seed1", kFirstWalk);
    second_ =
        test::sequenceTail(test::sharedSynthetic("walk_lap_seed2", kSecondWalk), 180, dir_ + "/b");
    test::mapTo(first_, dir_ + "/a.pcd");
  }
  // Where a run's frame lies in the room: its keyframes aligned to the truth.
  static Eigen::Isometry3d frameInWorld(const std::string& keyframes, const std::string& truth) {
    return absoluteTrajectoryError(Trajectory::load(keyframes), Trajectory::load(truth)).alignment;
  }
  std::string dir_, first_, second_;
};

TEST_F(RoomSessions, ASecondWalkIsLocalisedInTheFirstsMapWhichStaysAsItWas) {
  const std::string map_before = test::digest(dir_ + "/a.pcd");
  const std::string session_before = test::digest(dir_ + "/a.session");
  const test::Localised run = test::localise(second_, dir_ + "/a.session", dir_ + "/localised");
  ASSERT_EQ(run.code, 0) << run.log;
  EXPECT_NE(run.log.find("localisation: placed in the saved map at keyframe"), std::string::npos)
      << run.log;
  // Every frame has its pose; those before the saved map was recognised are counted (a few).
  ASSERT_EQ(run.trajectory.size(), 180u) << run.log;
  const double unplaced = test::jsonNumber(run.stats, "frames_unplaced");
  EXPECT_LE(unplaced, 30) << run.log;
  // Against the truth, in the frame the first run's keyframes align to theirs: one alignment,
  // made without the localised frames.
  const Eigen::Isometry3d saved_to_world =
      frameInWorld(dir_ + "/a_keyframes.txt", first_ + "/groundtruth.txt");
  const Trajectory truth = Trajectory::load(second_ + "/groundtruth.txt");
  std::vector<double> errors;
  for (const StampedPose& p : run.trajectory.poses()) {
    const auto true_pose = truth.interpolate(p.timestamp);
    ASSERT_TRUE(true_pose);
    errors.push_back(((saved_to_world * p.pose).translation() - true_pose->translation()).norm());
  }
  const ErrorStatistics e = errorStatistics(errors);
  std::cout << "localised in the saved map: " << errors.size() << " frames, " << unplaced
            << " before recognition; error median " << e.median * 100 << " cm, rmse "
            << e.rmse * 100 << " cm, max " << e.max * 100 << " cm\n";
  EXPECT_LT(e.median, 0.02);
  EXPECT_LT(e.max, 0.06);
  // Nothing mapped, nothing of the saved run's changed.
  EXPECT_FALSE(fs::exists(dir_ + "/localised.pcd"));
  EXPECT_FALSE(fs::exists(dir_ + "/localised.session"));
  EXPECT_EQ(test::digest(dir_ + "/a.pcd"), map_before);
  EXPECT_EQ(test::digest(dir_ + "/a.session"), session_before);
}

TEST_F(RoomSessions, TwoWalksMergeInTheFirstsFrameAndARunElsewhereIsLeftOut) {
  test::mapTo(second_, dir_ + "/b.pcd");
  test::mapTo(test::tumDir("rgbd_dataset_freiburg1_xyz"), dir_ + "/c.pcd");  // a real desk
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " merge " + dir_ + "/a.session " + dir_ + "/b.session " +
                          dir_ + "/c.session --out " + dir_ + "/merged.pcd",
                      &output),
            0)
      << output;
  EXPECT_NE(output.find(dir_ + "/c.session: shares no place with the other sessions: left out"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("merged 2 of 3 sessions"), std::string::npos) << output;
  const std::string transforms = dir_ + "/merged_transforms.txt";
  EXPECT_FALSE(test::mergedTransformOf(transforms, dir_ + "/c.session"));
  const auto b = test::mergedTransformOf(transforms, dir_ + "/b.session");
  ASSERT_TRUE(b) << test::readFile(transforms);

  // B's frame in A's against the truth: both runs' frames located in the room.
  const Eigen::Isometry3d truth =
      frameInWorld(dir_ + "/a_keyframes.txt", first_ + "/groundtruth.txt").inverse() *
      frameInWorld(dir_ + "/b_keyframes.txt", second_ + "/groundtruth.txt");
  const Eigen::Isometry3d error = truth.inverse() * *b;
  const double degrees = Eigen::AngleAxisd(error.linear()).angle() * 57.29577951308232;
  std::cout << "B's frame in A's: " << error.translation().norm() * 100 << " cm and " << degrees
            << " degrees from the truth\n";
  EXPECT_LT(error.translation().norm(), 0.02);
  EXPECT_LT(degrees, 1.0);

  // One map: as precise as A's own (B placed a little off would leave a second layer).
  const double alone = test::precisionOf(dir_ + "/a.pcd", first_, dir_ + "/a_keyframes.txt");
  const double merged = test::precisionOf(dir_ + "/merged.pcd", first_, dir_ + "/a_keyframes.txt");
  std::cout << "precision at 1 cm: merged " << merged << ", the first run alone " << alone << "\n";
  EXPECT_GE(merged, alone - 0.005);
  EXPECT_GE(merged, 0.99);
  EXPECT_GT(test::loadMap(dir_ + "/merged.pcd").size(), test::loadMap(dir_ + "/a.pcd").size());
  // The merged session reads back.
  EXPECT_EQ(test::run(test::binary() + " session " + dir_ + "/merged.session", &output), 0)
      << output;
}

}  // namespace
}  // namespace rgbdmap
