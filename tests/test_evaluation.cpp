// Trajectory metrics (TUM's ATE and RPE) and map scores against exact geometry, on inputs whose
// answers are known by construction.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>

#include <cmath>
#include <fstream>
#include <random>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/sim/synthetic_scene.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using V = Eigen::Vector3d;

Eigen::Isometry3d rigid(double angle, const V& axis, const V& translation) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  t.translation() = translation;
  return t;
}

// A circle of radius 1 in the xy plane at 30 Hz for `seconds`, camera turning with it.
Trajectory circle(double seconds, double rate = 30.0) {
  Trajectory trajectory;
  for (int i = 0; i <= static_cast<int>(seconds * rate); ++i) {
    const double t = i / rate, a = 0.5 * t;
    trajectory.push_back({1000.0 + t, rigid(a, V::UnitZ(), V(std::cos(a), std::sin(a), 1.0))});
  }
  return trajectory;
}

TEST(TrajectoryEvaluation, HornAlignmentRecoversAKnownRigidTransform) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> coordinate(-2.0, 2.0);
  std::vector<V> from, to;
  const Eigen::Isometry3d truth = rigid(0.7, V(1, 2, 3), V(0.5, -1.0, 2.0));
  for (int i = 0; i < 50; ++i) {
    from.emplace_back(coordinate(random), coordinate(random), coordinate(random));
    to.push_back(truth * from.back());
  }
  const Eigen::Isometry3d found = alignRigid(from, to);
  EXPECT_TRUE(found.matrix().isApprox(truth.matrix(), 1e-12)) << found.matrix();
  EXPECT_THROW(alignRigid({V::Zero(), V::Ones()}, {V::Zero(), V::Ones()}), std::invalid_argument);
}

TEST(TrajectoryEvaluation, AteOfARigidlyMovedGroundTruthIsZero) {
  const Trajectory groundtruth = circle(10.0, 100.0);
  const Eigen::Isometry3d moved = rigid(1.1, V(0.3, -1, 0.2), V(3, -2, 0.5));
  Trajectory estimate;
  for (std::size_t i = 0; i < groundtruth.size(); i += 3)
    estimate.push_back({groundtruth[i].timestamp, moved * groundtruth[i].pose});
  const AbsoluteTrajectoryError ate = absoluteTrajectoryError(estimate, groundtruth);
  EXPECT_EQ(ate.translation.count, estimate.size());
  EXPECT_LT(ate.translation.rmse, 1e-9);
  EXPECT_LT(ate.translation.max, 1e-9);
  EXPECT_TRUE(ate.alignment.matrix().isApprox(moved.inverse().matrix(), 1e-9));
  // The relative motions of a rigidly moved trajectory are the same: RPE zero too.
  const RelativePoseError rpe = relativePoseError(estimate, groundtruth);
  EXPECT_LT(rpe.translation.max, 1e-9);
  EXPECT_LT(rpe.rotation.max, 1e-6);
}

// A camera carried at one height: its positions leave the tilt of the alignment to their noise,
// its views do not. Estimated positions with 2 mm noise and orientations 0.01 deg off.
TEST(TrajectoryEvaluation, ViewsFixTheTiltThatPositionsAtOneHeightLeaveOpen) {
  const Trajectory groundtruth = circle(12.0);
  const Eigen::Isometry3d moved = rigid(0.4, V(0.2, 1, -0.3), V(1, 2, -0.5));
  std::mt19937 random(11);
  std::normal_distribution<double> noise(0.0, 0.002), angle(0.0, 0.0002);
  Trajectory estimate;
  for (std::size_t i = 0; i < groundtruth.size(); ++i) {
    const StampedPose& g = groundtruth[i];
    Eigen::Isometry3d p = g.pose;
    p.translation() += V(noise(random), noise(random), noise(random));
    p.linear() = p.linear() * rigid(angle(random), V(1, 2, 3), V::Zero()).linear();
    estimate.push_back({g.timestamp, moved * p});
  }
  auto tiltError = [&](const Eigen::Isometry3d& alignment) {
    const V up = (alignment * moved).linear() * V::UnitZ();
    return std::acos(std::min(1.0, up.dot(V::UnitZ())));
  };
  const double by_positions = tiltError(absoluteTrajectoryError(estimate, groundtruth).alignment);
  const double by_views = tiltError(alignViews(estimate, groundtruth));
  EXPECT_LT(by_views, 0.0002);  // 0.01 deg
  EXPECT_LT(by_views, by_positions / 3);
  // Exact when the estimate is a rigidly moved groundtruth.
  Trajectory exact;
  for (std::size_t i = 0; i < groundtruth.size(); ++i)
    exact.push_back({groundtruth[i].timestamp, moved * groundtruth[i].pose});
  EXPECT_TRUE(alignViews(exact, groundtruth).matrix().isApprox(moved.inverse().matrix(), 1e-9));
  EXPECT_THROW(alignViews(Trajectory{}, groundtruth), InputError);
}

TEST(TrajectoryEvaluation, AteOfAScaledCircleIsTheScaleErrorTimesTheRadius) {
  // A rigid alignment cannot undo scale: every position of a circle of radius 1 scaled by 1.1
  // about its centre stays 0.1 m off, so RMSE = mean = median = max = 0.1 m.
  const Trajectory groundtruth = circle(4.0 * M_PI);  // exactly one turn (0.5 rad/s)
  Trajectory estimate;
  for (const StampedPose& p : groundtruth.poses()) {
    StampedPose q = p;
    q.pose.translation() = V(1.1 * p.pose.translation().x(), 1.1 * p.pose.translation().y(), 1.0);
    estimate.push_back(q);
  }
  const AbsoluteTrajectoryError ate = absoluteTrajectoryError(estimate, groundtruth);
  EXPECT_NEAR(ate.translation.rmse, 0.1, 1e-3);
  EXPECT_NEAR(ate.translation.mean, 0.1, 1e-3);
  EXPECT_NEAR(ate.translation.median, 0.1, 1e-3);
  EXPECT_NEAR(ate.translation.max, 0.1, 1e-3);
}

TEST(TrajectoryEvaluation, AteUsesOnlyStampsWithinTheAssociationWindow) {
  const Trajectory groundtruth = circle(5.0, 5.0);  // 5 Hz: stamps 0.2 s apart
  Trajectory estimate;
  for (const StampedPose& p : groundtruth.poses()) estimate.push_back({p.timestamp + 0.03, p.pose});
  EXPECT_THROW(absoluteTrajectoryError(estimate, groundtruth), InputError);  // 30 ms > 20 ms
  Trajectory close;
  for (const StampedPose& p : groundtruth.poses()) close.push_back({p.timestamp + 0.015, p.pose});
  EXPECT_EQ(absoluteTrajectoryError(close, groundtruth).translation.count, groundtruth.size());
}

TEST(TrajectoryEvaluation, RpeOfATranslationDriftIsTheDriftPerInterval) {
  // Ground truth turns on a circle; the estimate drifts 5 cm/s along world x. Over 1 s the
  // estimated motion differs from the true one by 5 cm in the world, expressed in camera i's
  // frame: |error translation| = 0.05 m, no rotation error.
  const Trajectory groundtruth = circle(5.0);
  Trajectory estimate;
  for (const StampedPose& p : groundtruth.poses()) {
    StampedPose q = p;
    q.pose.translation() += V(0.05 * (p.timestamp - 1000.0), 0, 0);
    estimate.push_back(q);
  }
  const RelativePoseError rpe = relativePoseError(estimate, groundtruth, 1.0);
  // Pairs for i with t_i + 1 s before the last pose (t = 5 s): t_i in [0, 4), 120 at 30 Hz.
  EXPECT_EQ(rpe.translation.count, 120u);
  EXPECT_NEAR(rpe.translation.rmse, 0.05, 1e-9);
  EXPECT_NEAR(rpe.translation.mean, 0.05, 1e-9);
  EXPECT_LT(rpe.rotation.max, 1e-6);
}

TEST(TrajectoryEvaluation, RpeOfARotationDriftIsTheAnglePerInterval) {
  // A camera standing still whose estimate turns 3 degrees per second about its own y axis.
  Trajectory groundtruth, estimate;
  for (int i = 0; i <= 150; ++i) {
    const double t = i / 30.0;
    groundtruth.push_back({t, Eigen::Isometry3d::Identity()});
    estimate.push_back({t, rigid(3.0 * M_PI / 180.0 * t, V::UnitY(), V::Zero())});
  }
  const RelativePoseError rpe = relativePoseError(estimate, groundtruth, 1.0);
  EXPECT_NEAR(rpe.rotation.rmse, 3.0, 1e-9);
  EXPECT_NEAR(rpe.rotation.max, 3.0, 1e-9);
  EXPECT_LT(rpe.translation.max, 1e-12);
  // The ATE of positions that never moved is zero whatever the orientation.
  EXPECT_LT(absoluteTrajectoryError(estimate, groundtruth).translation.max, 1e-12);
}

// Exact surface samples: ray hits from a few points inside the room in random directions.
pcl::PointCloud<pcl::PointXYZRGB> samplesOnScene(const SyntheticScene& scene, int count,
                                                 double offset_along_normal = 0.0) {
  std::mt19937 random(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const std::vector<V> viewpoints = {V(0, 0, 1.4), V(0.8, 0.5, 1.2), V(-0.8, -0.4, 1.6)};
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  for (int i = 0; i < count; ++i) {
    const V& origin = viewpoints[static_cast<std::size_t>(i) % viewpoints.size()];
    const V direction(gauss(random), gauss(random), gauss(random));
    double t = 0.0;
    V normal;
    cv::Vec3b color;
    if (!scene.raycast(origin, direction, t, normal, color)) continue;
    // The normal faces the viewpoint: a positive offset moves the point into free space.
    const V p = origin + t * direction + offset_along_normal * normal;
    pcl::PointXYZRGB point;
    point.x = static_cast<float>(p.x());
    point.y = static_cast<float>(p.y());
    point.z = static_cast<float>(p.z());
    cloud.push_back(point);
  }
  return cloud;
}

pcl::PointCloud<pcl::PointXYZ> positions(const pcl::PointCloud<pcl::PointXYZRGB>& cloud) {
  pcl::PointCloud<pcl::PointXYZ> out;
  for (const auto& p : cloud) out.push_back(pcl::PointXYZ(p.x, p.y, p.z));
  return out;
}

// A continued run's trajectory holds the saved run's poses first, and the saved run may have been
// recorded later (a replay of an older sequence): read in time order. One pose a time.
TEST(TrajectoryFile, RunsOutOfTimeOrderAreReadInOrderAndARepeatedStampIsRefused) {
  const std::string dir = test::freshDir();
  std::ofstream(dir + "/runs.txt") << "# timestamp tx ty tz qx qy qz qw\n"
                                   << "20.0 2 0 0 0 0 0 1\n21.0 3 0 0 0 0 0 1\n"
                                   << "10.0 0 0 0 0 0 0 1\n11.0 1 0 0 0 0 0 1\n";
  const Trajectory runs = Trajectory::load(dir + "/runs.txt");
  ASSERT_EQ(runs.size(), 4u);
  for (std::size_t i = 0; i < runs.size(); ++i)
    EXPECT_DOUBLE_EQ(runs[i].pose.translation().x(), static_cast<double>(i));
  EXPECT_DOUBLE_EQ(runs[0].timestamp, 10.0);
  std::ofstream(dir + "/twice.txt") << "10.0 0 0 0 0 0 0 1\n11.0 1 0 0 0 0 0 1\n"
                                    << "10.0 2 0 0 0 0 0 1\n";
  try {
    Trajectory::load(dir + "/twice.txt");
    ADD_FAILURE() << "a repeated timestamp was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/twice.txt: timestamp 10.000000 appears on two"),
              std::string::npos)
        << e.what();
  }
}

TEST(MapEvaluation, PointsOnTheSurfaceArePreciseAndComplete) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  const auto map = samplesOnScene(scene, 30000);
  const MapScore score = evaluateMap(map, scene, positions(map), 0.01);
  EXPECT_EQ(score.map_points, map.size());
  EXPECT_DOUBLE_EQ(score.precision, 1.0);
  EXPECT_DOUBLE_EQ(score.recall, 1.0);
  EXPECT_DOUBLE_EQ(score.f_score, 1.0);
  EXPECT_LT(score.mean_distance, 1e-6);  // float storage only
  EXPECT_LT(score.p95_distance, 1e-6);
}

TEST(MapEvaluation, PointsTwoCentimetresOffFailATauOfOneCentimetre) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  const auto reference = samplesOnScene(scene, 30000);
  const auto shifted = samplesOnScene(scene, 30000, 0.02);
  const MapScore score = evaluateMap(shifted, scene, positions(reference), 0.01);
  // Only points shifted towards another surface (in corners) can come within 1 cm of it.
  EXPECT_LT(score.precision, 0.02);
  EXPECT_LT(score.recall, 0.02);
  EXPECT_NEAR(score.median_distance, 0.02, 1e-6);
  // At tau = 3 cm the same map is precise and complete.
  const MapScore loose = evaluateMap(shifted, scene, positions(reference), 0.03);
  EXPECT_DOUBLE_EQ(loose.precision, 1.0);
  EXPECT_GT(loose.recall, 0.99);
}

TEST(MapEvaluation, RecallDropsWhenHalfTheMapIsMissing) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  const auto full = samplesOnScene(scene, 30000);
  pcl::PointCloud<pcl::PointXYZRGB> half;
  for (const auto& p : full)
    if (p.x < 0.0f) half.push_back(p);
  const MapScore score = evaluateMap(half, scene, positions(full), 0.01);
  const double expected = static_cast<double>(half.size()) / full.size();
  EXPECT_DOUBLE_EQ(score.precision, 1.0);
  // Reference points with x >= 0 have no map point within 1 cm, except along the cut.
  EXPECT_NEAR(score.recall, expected, 0.01);
  EXPECT_GT(score.recall, 0.3);
  EXPECT_LT(score.recall, 0.7);
  EXPECT_NEAR(score.f_score, 2 * score.recall / (1 + score.recall), 1e-12);
}

TEST(MapEvaluation, EmptyMapScoresZero) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  const MapScore score = evaluateMap(pcl::PointCloud<pcl::PointXYZRGB>(), scene,
                                     positions(samplesOnScene(scene, 100)));
  EXPECT_EQ(score.map_points, 0u);
  EXPECT_EQ(score.precision, 0.0);
  EXPECT_EQ(score.recall, 0.0);
  EXPECT_EQ(score.f_score, 0.0);
}

TEST(MapEvaluation, BadFilesAreNamed) {
  const std::string dir = test::freshDir();
  auto expectNamed = [](auto&& call, const std::string& name) {
    try {
      call();
      ADD_FAILURE() << "expected an InputError naming " << name;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  expectNamed([&] { loadMapFile(dir + "/missing.pcd"); }, dir + "/missing.pcd");
  std::ofstream(dir + "/garbage.pcd") << "this is not a point cloud\n";
  expectNamed([&] { loadMapFile(dir + "/garbage.pcd"); }, dir + "/garbage.pcd");
  std::ofstream(dir + "/map.xyz") << "1 2 3\n";
  expectNamed([&] { loadMapFile(dir + "/map.xyz"); }, dir + "/map.xyz");
  expectNamed([&] { loadSyntheticGroundTruth(dir); }, dir + "/scene.yaml");
  SyntheticScene::defaultRoom().save(dir + "/scene.yaml");
  expectNamed([&] { loadSyntheticGroundTruth(dir); }, dir + "/visible_surface.pcd");
}

TEST(EvaluateCommand, ReportsBadInputWithTheFileNameAndFails) {
  const std::string dir = test::freshDir();
  std::string output;
  EXPECT_NE(
      test::run(test::binary() + " evaluate map " + dir + "/none.pcd --scene " + dir, &output), 0);
  EXPECT_NE(output.find(dir + "/scene.yaml"), std::string::npos) << output;
  std::ofstream(dir + "/estimate.txt") << "1.0 0 0 0 0 0 0 1\n2.0 0 0 nan 0 0 0 1\n";
  const Trajectory gt = circle(3.0);
  gt.save(dir + "/gt.txt");
  EXPECT_NE(test::run(test::binary() + " evaluate trajectory --estimate " + dir +
                          "/estimate.txt --groundtruth " + dir + "/gt.txt",
                      &output),
            0);
  EXPECT_NE(output.find(dir + "/estimate.txt:2"), std::string::npos) << output;
  // An alignment the command does not know is named, not guessed.
  EXPECT_NE(test::run(test::binary() + " evaluate map " + dir + "/none.pcd --scene " + dir +
                          " --trajectory " + dir + "/gt.txt --align sideways",
                      &output),
            0);
  EXPECT_NE(output.find("--align"), std::string::npos) << output;
}

TEST(EvaluateCommand, TrajectoryTableAndJson) {
  const std::string dir = test::freshDir();
  const Trajectory gt = circle(5.0);
  Trajectory estimate;
  for (const StampedPose& p : gt.poses()) {
    StampedPose q = p;
    q.pose.translation() += V(0.05 * (p.timestamp - 1000.0), 0, 0);
    estimate.push_back(q);
  }
  gt.save(dir + "/gt.txt");
  estimate.save(dir + "/estimate.txt");
  std::string output;
  ASSERT_EQ(
      test::run(test::binary() + " evaluate trajectory --estimate " + dir +
                    "/estimate.txt --groundtruth " + dir + "/gt.txt --json " + dir + "/result.json",
                &output),
      0)
      << output;
  EXPECT_NE(output.find("ATE"), std::string::npos) << output;
  EXPECT_NE(output.find("RPE"), std::string::npos) << output;
  const std::string json = test::readFile(dir + "/result.json");
  // The drift of 5 cm/s is an RPE of 5 cm per second (files carry 7 decimals).
  EXPECT_NE(json.find("\"rpe_trans_rmse_m\": 0.0500"), std::string::npos) << json;
  EXPECT_NE(json.find("\"ate_rmse_m\""), std::string::npos) << json;
}

}  // namespace
}  // namespace rgbdmap
