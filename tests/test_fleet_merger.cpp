// FleetMerger (rgbdmap_merger's core) on streamed sessions: a robot that drives a route already
// mapped is placed where it is, one elsewhere is not, a restarted robot's old run stays, and the
// merged map, fused from the robots' map pieces, is one surface where they saw the same.

#include <gtest/gtest.h>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/sessions/fleet_merger.hpp"
#include "rgbdmap/slam/motion.hpp"
#include "session_runs.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using test::rpySession;

// The session moved into another frame (a second robot starting elsewhere in the same place).
Session movedSession(const Session& s, const Eigen::Isometry3d& frame) {
  Session out = s;
  for (auto& k : out.graph.keyframes) {
    k.pose = frame * k.pose;
    k.odometry = frame * k.odometry;
  }
  for (auto& kept : out.keyframes) kept.pose = frame * kept.pose;
  return out;
}

TEST(FleetMerger, ARobotOnAMappedRouteIsPlacedWhereItIs) {
  const Session& rpy = rpySession();
  Eigen::Isometry3d elsewhere = Eigen::Isometry3d::Identity();
  elsewhere.linear() = Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  elsewhere.translation() = Eigen::Vector3d(2.0, 0.0, -1.0);
  FleetMerger merger({"/robot1", "/robot2"}, Config{});
  EXPECT_FALSE(merger.merge());  // nothing yet
  EXPECT_EQ(test::send(merger, 0, rpy, 11, "/robot1/rgbdmap/session/graph"), 0u);
  test::send(merger, 1, movedSession(rpy, elsewhere), 22, "/robot2/rgbdmap/session/graph");
  ASSERT_TRUE(merger.merge());
  EXPECT_FALSE(merger.merge());  // nothing new since
  const auto robots = merger.robots();
  ASSERT_TRUE(robots[1].placed);
  EXPECT_EQ(robots[1].linked_to, "/robot1");
  EXPECT_GE(robots[1].links, 2);
  // Robot 2's frame in robot 1's: the inverse of the move.
  const Eigen::Isometry3d error = elsewhere * robots[1].transform;
  EXPECT_LT(error.translation().norm(), 0.005);
  EXPECT_LT(rotationAngle(error), 0.005);
  EXPECT_EQ(merger.session().graph.keyframes.size(), 2 * rpy.graph.keyframes.size());

  // The map: both robots' pieces (the same views) fused at the merged poses are one surface, as
  // many points as robot 1's alone, where the two robots' own maps put together were twice as
  // many. (How precise a map of pieces is: the next test, against exact geometry.)
  const MapCloud merged = merger.map();
  FleetMerger one({"/robot1"}, Config{});
  test::send(one, 0, rpy, 11, "/robot1/x");
  one.merge();
  const MapCloud alone = one.map();
  ASSERT_GT(alone.size(), 100000u);
  EXPECT_LT(merged.size(), 1.1 * alone.size()) << merged.size() << " vs " << alone.size();
  EXPECT_GT(merged.size(), 0.9 * alone.size()) << merged.size() << " vs " << alone.size();
}

TEST(FleetMerger, AMergerRestartedFromItsSavedSessionPicksUpAgain) {
  const Session& rpy = rpySession();
  Eigen::Isometry3d elsewhere = Eigen::Isometry3d::Identity();
  elsewhere.translation() = Eigen::Vector3d(1.0, 0.0, 0.5);
  FleetMerger first({"/robot1", "/robot2"}, Config{});
  test::send(first, 0, rpy, 11, "/robot1/x");
  test::send(first, 1, movedSession(rpy, elsewhere), 22, "/robot2/x");
  first.merge();
  const std::size_t points = first.map().size();
  ASSERT_TRUE(first.robots()[1].placed);
  const std::string dir = test::freshDir();
  std::string error;
  ASSERT_TRUE(writeSession(first.session(), dir + "/merged.session", error)) << error;

  // Restarted: both robots back where they were, and the map, before either sends anything.
  const Session saved = readSession(dir + "/merged.session");
  ASSERT_EQ(saved.streams.size(), 2u);
  FleetMerger again({"/robot1", "/robot2"}, Config{});
  EXPECT_EQ(again.resume(saved, dir + "/merged.session"), 2u);
  ASSERT_TRUE(again.merge());
  auto robots = again.robots();
  ASSERT_TRUE(robots[1].placed);
  const Eigen::Isometry3d moved = first.robots()[1].transform.inverse() * robots[1].transform;
  EXPECT_LT(moved.translation().norm(), 0.002);
  EXPECT_EQ(robots[1].keyframes, rpy.graph.keyframes.size());
  EXPECT_NEAR(static_cast<double>(again.map().size()), static_cast<double>(points),
              0.02 * static_cast<double>(points));
  // Robot 1 did not notice and sends everything again (a merger asked): nothing twice.
  test::send(again, 0, rpy, 11, "/robot1/x");
  again.merge();
  robots = again.robots();
  EXPECT_EQ(robots[0].keyframes, rpy.graph.keyframes.size());
  EXPECT_EQ(robots[0].runs, 1u);
  EXPECT_EQ(again.session().graph.keyframes.size(), 2 * rpy.graph.keyframes.size());
  EXPECT_NEAR(static_cast<double>(again.map().size()), static_cast<double>(points),
              0.02 * static_cast<double>(points));
  // A robot not among the merger's now is left out.
  FleetMerger other({"/robot1", "/robot3"}, Config{});
  EXPECT_EQ(other.resume(saved, dir + "/merged.session"), 1u);
}

TEST(FleetMerger, ARobotElsewhereStaysUnplacedAndARestartKeepsTheOldRun) {
  const Session& rpy = rpySession();
  FleetMerger merger({"/robot1", "/robot2"}, Config{});
  test::send(merger, 0, rpy, 1, "/robot1/x");
  // Robot 2 saw something else: the same keyframes with places of no resemblance.
  Session other = rpy;
  for (auto& place : other.graph.places)
    if (place) {
      auto blank = std::make_shared<PlaceRecognition::Place>(*place);
      // (A new matrix: the place's own is shared with the session, and a matrix expression
      // would be written into it.)
      blank->view.descriptors = cv::Mat(place->view.descriptors.size(),
                                        place->view.descriptors.type(), cv::Scalar::all(0));
      place = blank;
    }
  test::send(merger, 1, other, 2, "/robot2/x");
  merger.merge();
  EXPECT_FALSE(merger.robots()[1].placed);
  EXPECT_GT(merger.robots()[1].keyframes, 0u);

  // Robot 1 restarts: a new run, the old one kept beside it.
  test::send(merger, 0, rpy, 3, "/robot1/x");
  merger.merge();
  const auto robots = merger.robots();
  EXPECT_EQ(robots[0].runs, 2u);
  EXPECT_EQ(robots[0].keyframes, 2 * rpy.graph.keyframes.size());
  EXPECT_TRUE(robots[0].placed);
  // A record that is not one is refused naming its topic; nothing changes.
  EXPECT_THROW(merger.receive(0, "not a record", "/robot1/x"), InputError);
}

}  // namespace
}  // namespace rgbdmap
