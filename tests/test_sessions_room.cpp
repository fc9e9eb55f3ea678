// Sessions at the scale of a room (release build only: each test maps a lap of the synthetic
// room): a second run localised in the first run's map, and two runs merged into one map.

#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "rgbdmap/config/config.hpp"
#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/sessions/fleet_merger.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/sessions/session_merge.hpp"
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
    a_ = test::sharedMap("walk_lap_seed1", first_);
  }
  std::string dir_, first_, second_, a_;  // a_: the first walk's map (its path but extension)
};

TEST_F(RoomSessions, ASecondWalkIsLocalisedInTheFirstsMapWhichStaysAsItWas) {
  const std::string map_before = test::digest(a_ + ".pcd");
  const std::string session_before = test::digest(a_ + ".session");
  const test::SessionRun run = test::localise(second_, a_ + ".session", dir_ + "/localised");
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
      test::frameInWorld(a_ + "_keyframes.txt", first_ + "/groundtruth.txt");
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
  EXPECT_EQ(test::digest(a_ + ".pcd"), map_before);
  EXPECT_EQ(test::digest(a_ + ".session"), session_before);
}

// A continued session's keyframes, the saved run's (ids below `saved`) or the new one's, at the
// graph's optimised poses, moved `by`, with their timestamps shifted by `shift` s.
Trajectory partOf(const Session& session, std::size_t saved, bool saved_part,
                  const Eigen::Isometry3d& by = Eigen::Isometry3d::Identity(), double shift = 0) {
  Trajectory out;
  for (std::size_t id = 0; id < session.graph.keyframes.size(); ++id)
    if ((id < saved) == saved_part)
      out.push_back(
          {session.graph.keyframes[id].timestamp + shift, by * session.graph.keyframes[id].pose});
  return out;
}

Trajectory shifted(const Trajectory& t, double shift) {
  Trajectory out;
  for (const StampedPose& p : t.poses()) out.push_back({p.timestamp + shift, p.pose});
  return out;
}

TEST_F(RoomSessions, ASecondWalkContinuesTheFirstsMapAsOneMap) {
  const std::string map_before = test::digest(a_ + ".pcd");
  const std::size_t saved = readSession(a_ + ".session").graph.keyframes.size();
  const test::SessionRun run = test::continueFrom(second_, a_ + ".session", dir_ + "/b");
  ASSERT_EQ(run.code, 0) << run.log;
  EXPECT_NE(run.log.find("continuing: keyframe"), std::string::npos) << run.log;
  // The saved map is recognised within a few frames of the start (it starts on ground the
  // first walk saw).
  const double unplaced = test::jsonNumber(run.stats, "frames_unplaced");
  EXPECT_LE(unplaced, 30) << run.log;
  EXPECT_EQ(test::digest(a_ + ".pcd"), map_before);

  // Both runs' keyframes in the continued session's one graph, scored against the truth in one
  // alignment (the second run's clock shifted: the two walks share their timestamps).
  const Session both = readSession(dir_ + "/b.session");
  ASSERT_GT(both.graph.keyframes.size(), saved + 20) << run.log;
  const double kShift = 1000.0;
  const Trajectory estimate = test::merged(
      partOf(both, saved, true), partOf(both, saved, false, Eigen::Isometry3d::Identity(), kShift));
  const Trajectory truth =
      test::merged(Trajectory::load(first_ + "/groundtruth.txt"),
                   shifted(Trajectory::load(second_ + "/groundtruth.txt"), kShift));
  const AbsoluteTrajectoryError ate = absoluteTrajectoryError(estimate, truth);
  std::cout << "continued: " << unplaced << " frames before recognition; both runs' keyframes ATE "
            << ate.translation.rmse * 100 << " cm in one alignment\n";
  EXPECT_LT(ate.translation.rmse, 0.005);

  // One map, as the graph has it: precise and complete where the first walk looked (a second
  // layer from the second run placed off would cost precision), and no bigger than the two runs'
  // keyframes fused into one TSDF by `rgbdmap merge` (plus 10%).
  const std::string aligned = dir_ + "/b_saved_part.txt";
  partOf(both, saved, true).save(aligned);
  const std::string score = dir_ + "/b.score.json";
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " evaluate map " + dir_ + "/b.pcd --scene " + first_ +
                          " --trajectory " + aligned + " --json " + score,
                      &output),
            0)
      << output;
  const double precision = test::jsonNumber(test::readFile(score), "precision");
  const double recall = test::jsonNumber(test::readFile(score), "recall");
  const std::string b_alone = test::sharedMap("walk_lap_seed2_second_half", second_);
  const std::size_t points = test::loadMap(dir_ + "/b.pcd").size();
  const std::size_t merged =
      test::mergedPoints(a_ + ".session", b_alone + ".session", dir_ + "/merged.pcd");
  std::cout << "continued map: precision " << precision << ", recall " << recall << " at 1 cm; "
            << points << " points, merged offline " << merged << "\n";
  EXPECT_GE(precision, 0.995);
  EXPECT_GE(recall, 0.98);
  EXPECT_LE(static_cast<double>(points), 1.1 * static_cast<double>(merged));
}

TEST_F(RoomSessions, TwoWalksMergeInTheFirstsFrameAndARunElsewhereIsLeftOut) {
  const std::string b_map = test::sharedMap("walk_lap_seed2_second_half", second_);
  const std::string c_map = test::sharedMap(test::kXyz, test::tumDir(test::kXyz));  // a real desk
  const std::vector<std::string> sessions = {a_ + ".session", b_map + ".session",
                                             c_map + ".session"};
  const test::MergeRun merge = test::mergeSessions(sessions, dir_ + "/merged.pcd");
  test::expectAllButOneJoined(merge, sessions, 2);
  ASSERT_TRUE(merge.transforms[1]) << merge.log;
  const Eigen::Isometry3d b = *merge.transforms[1];

  // B's frame in A's against the truth: both runs' frames located in the room.
  const Eigen::Isometry3d truth =
      test::frameInWorld(a_ + "_keyframes.txt", first_ + "/groundtruth.txt").inverse() *
      test::frameInWorld(b_map + "_keyframes.txt", second_ + "/groundtruth.txt");
  const Eigen::Isometry3d error = truth.inverse() * b;
  const double degrees = Eigen::AngleAxisd(error.linear()).angle() * 57.29577951308232;
  std::cout << "B's frame in A's: " << error.translation().norm() * 100 << " cm and " << degrees
            << " degrees from the truth\n";
  EXPECT_LT(error.translation().norm(), 0.02);
  EXPECT_LT(degrees, 1.0);

  // One map: as precise as A's own (B placed a little off would leave a second layer).
  const double alone = test::precisionOf(a_ + ".pcd", first_, a_ + "_keyframes.txt");
  const double merged = test::precisionOf(dir_ + "/merged.pcd", first_, a_ + "_keyframes.txt");
  std::cout << "precision at 1 cm: merged " << merged << ", the first run alone " << alone << "\n";
  EXPECT_GE(merged, alone - 0.005);
  EXPECT_GE(merged, 0.99);
  EXPECT_GT(test::loadMap(dir_ + "/merged.pcd").size(), test::loadMap(a_ + ".pcd").size());
}

TEST_F(RoomSessions, TwoRobotsStreamsArePlacedByTheirPlacesAlone) {
  // A fleet's merger has no images: each robot's places (ORB features, packed dense reference)
  // must place it (PlaceMatcher: PnP, dense alignment to the view drawn from the reference,
  // agreement of two or more).
  const std::string b_map = test::sharedMap("walk_lap_seed2_second_half", second_);
  const std::string c_map = test::sharedMap(test::kXyz, test::tumDir(test::kXyz));  // a real desk
  const Session a = test::streamed(readSession(a_ + ".session"));
  const Session b = test::streamed(readSession(b_map + ".session"));
  const Session c = test::streamed(readSession(c_map + ".session"));
  ASSERT_TRUE(a.keyframes.empty() && b.keyframes.empty());
  std::vector<SessionMerger::Placement> placements;
  Config settings;
  SessionMerger(settings).merge({a, c, b}, placements);
  EXPECT_FALSE(placements[1].placed);  // elsewhere: shares no place
  ASSERT_TRUE(placements[2].placed);
  EXPECT_EQ(placements[2].linked_to, 0);
  placements.erase(placements.begin() + 1);
  const Eigen::Isometry3d truth =
      test::frameInWorld(a_ + "_keyframes.txt", first_ + "/groundtruth.txt").inverse() *
      test::frameInWorld(b_map + "_keyframes.txt", second_ + "/groundtruth.txt");
  const Eigen::Isometry3d error = truth.inverse() * placements[1].transform;
  const double degrees = Eigen::AngleAxisd(error.linear()).angle() * 57.29577951308232;
  std::cout << "robot B placed by " << placements[1].links
            << " places: " << error.translation().norm() * 100 << " cm and " << degrees
            << " degrees from the truth\n";
  EXPECT_LT(error.translation().norm(), 0.02);
  EXPECT_LT(degrees, 1.0);

  // The fleet's merger gets robot B's records one by one (its graph, then its places, then its
  // map pieces), a merge after each: once B is placed, each new place of B is compared only
  // with A's places near where the merged graph puts it. B ends as tied as by the one merge
  // above, which compared every place of B with every place of A, for a fraction of the
  // comparisons.
  FleetMerger fleet({"/a", "/b"}, settings);
  test::send(fleet, 0, readSession(a_ + ".session"), 1, "/a/x");
  for (const std::string& record : test::streamOf(readSession(b_map + ".session"), 1)) {
    fleet.receive(1, record, "/b/x");
    fleet.merge();
  }
  const FleetMerger::Robot robot_b = fleet.robots()[1];
  ASSERT_TRUE(robot_b.placed);
  std::size_t places_a = 0, places_b = 0;
  for (const auto& p : a.graph.places) places_a += p ? 1 : 0;
  for (const auto& p : b.graph.places) places_b += p ? 1 : 0;
  std::cout << "the fleet's merger: B tied by " << robot_b.links
            << " places (one merge: " << placements[1].links << "), " << robot_b.compared
            << " place pairs compared (of " << places_a * places_b << ")\n";
  EXPECT_GE(robot_b.links, placements[1].links - 2);
  EXPECT_LT(robot_b.compared, places_a * places_b / 2);
  const Eigen::Isometry3d fleet_error = truth.inverse() * robot_b.transform;
  EXPECT_LT(fleet_error.translation().norm(), 0.02);
}

}  // namespace
}  // namespace rgbdmap
