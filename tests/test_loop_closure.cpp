// The parts of loop closure that need no camera: the pose graph pulling a drifted loop shut,
// corrections applied to anchored poses, and submaps merged into one layer.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

#include "rgbdmap/mapping/point_merger.hpp"
#include "rgbdmap/mapping/surface_cloud.hpp"
#include "rgbdmap/slam/pose_graph.hpp"
#include "rgbdmap/tracking/anchored_trajectory.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {
namespace {

Eigen::Isometry3d pose(double x, double y, double z, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

double rotationAngle(const Eigen::Isometry3d& t) { return Eigen::AngleAxisd(t.linear()).angle(); }

// A camera walking once round a circle of radius 2 m, 40 keyframes; the last one is where the
// first one was (rotated by a full turn).
std::vector<Eigen::Isometry3d> circle(int n) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    poses.push_back(pose(2.0 * std::cos(a), 2.0 * std::sin(a), 0.1 * std::sin(3 * a), a + M_PI_2));
  }
  return poses;
}

struct DriftedLoop {
  std::vector<Eigen::Isometry3d> truth, odometry;
  std::vector<PoseGraph::Edge> steps;
};

// Odometry steps with a small systematic error (scale 1.5 %, yaw 0.3 degrees per step) and
// noise: after a lap the odometry ends about 20 cm and 10 degrees from where it started.
DriftedLoop driftedLoop(int n) {
  DriftedLoop loop;
  loop.truth = circle(n);
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  loop.odometry.push_back(loop.truth[0]);
  for (int i = 1; i < n; ++i) {
    Eigen::Isometry3d step = loop.truth[i - 1].inverse() * loop.truth[i];
    step.translation() =
        step.translation() * 1.015 + Eigen::Vector3d(noise(random), noise(random), noise(random));
    step.linear() = step.linear() * Eigen::AngleAxisd(0.005, Eigen::Vector3d::UnitZ());
    loop.odometry.push_back(loop.odometry.back() * step);
    PoseGraph::Edge edge;
    edge.from = i - 1;
    edge.to = i;
    edge.measurement = step;
    loop.steps.push_back(edge);
  }
  return loop;
}

double meanError(const PoseGraph& graph, const std::vector<Eigen::Isometry3d>& truth) {
  double sum = 0;
  for (int i = 0; i < graph.size(); ++i)
    sum += (graph.pose(i).translation() - truth[static_cast<std::size_t>(i)].translation()).norm();
  return sum / graph.size();
}

TEST(PoseGraph, OdometryAloneKeepsItsEstimates) {
  const DriftedLoop loop = driftedLoop(40);
  PoseGraph graph;
  for (const auto& p : loop.odometry) graph.addNode(p);
  for (const auto& e : loop.steps) graph.addEdge(e);
  const PoseGraph::Summary summary = graph.optimise();
  ASSERT_TRUE(summary.usable);
  for (int i = 0; i < graph.size(); ++i)
    EXPECT_LT((graph.pose(i).translation() - loop.odometry[i].translation()).norm(), 1e-6);
  EXPECT_LT(summary.final_cost, 1e-12);
}

TEST(PoseGraph, LoopEdgePullsTheDriftedLapShut) {
  const DriftedLoop loop = driftedLoop(40);
  PoseGraph graph;
  for (const auto& p : loop.odometry) graph.addNode(p);
  for (const auto& e : loop.steps) graph.addEdge(e);
  const double drift_before = meanError(graph, loop.truth);
  const double gap_before =
      (loop.odometry.back().translation() - loop.truth.back().translation()).norm();
  ASSERT_GT(gap_before, 0.1) << "the test's odometry should drift";

  // The loop: the last keyframe seen from the first, measured exactly.
  PoseGraph::Edge closure;
  closure.from = 0;
  closure.to = 39;
  closure.measurement = loop.truth[0].inverse() * loop.truth[39];
  closure.sqrt_information = 10.0 * PoseGraph::Matrix6d::Identity();
  closure.loop = true;
  graph.addEdge(closure);
  EXPECT_GT(graph.whitenedError(closure), 1.0);

  const PoseGraph::Summary summary = graph.optimise();
  ASSERT_TRUE(summary.usable);
  EXPECT_LT(summary.final_cost, summary.initial_cost / 20);
  EXPECT_LT(graph.whitenedError(closure), 0.5);
  EXPECT_LT((graph.pose(39).translation() - loop.truth[39].translation()).norm(), gap_before / 4);
  EXPECT_LT(meanError(graph, loop.truth), drift_before / 2);
  // Node 0 defines the world and does not move.
  EXPECT_LT((graph.pose(0).translation() - loop.truth[0].translation()).norm(), 1e-9);
  EXPECT_LT(rotationAngle(graph.pose(0).inverse() * loop.truth[0]), 1e-9);
}

TEST(PoseGraph, RemovingTheLoopEdgeRestoresOdometry) {
  const DriftedLoop loop = driftedLoop(20);
  PoseGraph graph;
  for (const auto& p : loop.odometry) graph.addNode(p);
  for (const auto& e : loop.steps) graph.addEdge(e);
  PoseGraph::Edge closure;
  closure.from = 0;
  closure.to = 19;
  closure.measurement = loop.truth[0].inverse() * loop.truth[19];
  closure.loop = true;
  graph.addEdge(closure);
  graph.removeLastEdges(1);
  EXPECT_EQ(graph.edges().size(), loop.steps.size());
  EXPECT_FALSE(graph.edges().back().loop);
}

TEST(PoseGraph, SqrtInformationIsARootAndNeverSingular) {
  PoseGraph::Matrix6d information = PoseGraph::Matrix6d::Zero();
  information.diagonal() << 400, 400, 100, 2500, 2500, 0;  // no information about yaw
  const PoseGraph::Matrix6d root = PoseGraph::sqrtInformation(information);
  // A root: R^T R gives the information back, up to a small floor where it had none.
  const PoseGraph::Matrix6d back = root.transpose() * root;
  EXPECT_LT((back - information).norm(), 0.01);
  Eigen::SelfAdjointEigenSolver<PoseGraph::Matrix6d> solver(back);
  EXPECT_GT(solver.eigenvalues().minCoeff(), 0.0);
  EXPECT_TRUE(root.allFinite());
}

TEST(PoseCorrections, AnchoredPosesFollowTheirKeyframe) {
  PoseCorrections corrections;
  AnchoredTrajectory trajectory;
  trajectory.push_back(1.0, pose(1, 0, 0, 0), -1);  // before the first keyframe
  trajectory.push_back(2.0, pose(2, 0, 0, 0), 0);
  trajectory.push_back(3.0, pose(3, 0, 0, 0), 1);
  trajectory.push_back(4.0, pose(4, 0, 0, 0), 5);  // a keyframe the graph has not taken in yet

  Trajectory before = trajectory.resolve(&corrections);
  ASSERT_EQ(before.size(), 4u);
  EXPECT_NEAR(before[2].pose.translation().x(), 3.0, 1e-12);

  PoseCorrections::Table table{pose(0, 0, 0, 0), pose(0, 0.5, 0, M_PI_2)};
  corrections.publish(table);
  EXPECT_EQ(corrections.version(), 1u);
  const Trajectory after = trajectory.resolve(&corrections);
  EXPECT_NEAR(after[0].pose.translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(after[1].pose.translation().x(), 2.0, 1e-12);
  // Keyframe 1's correction: a quarter turn, then 0.5 m along y.
  EXPECT_NEAR(after[2].pose.translation().x(), 0.0, 1e-12);
  EXPECT_NEAR(after[2].pose.translation().y(), 3.5, 1e-12);
  // Beyond the table: the newest correction.
  EXPECT_NEAR(after[3].pose.translation().y(), 4.5, 1e-12);
  // Without corrections: as tracked.
  EXPECT_NEAR(trajectory.resolve(nullptr)[2].pose.translation().x(), 3.0, 1e-12);
}

TEST(PoseCorrections, ASnapshotStaysAsTakenWhileANewTableIsPublished) {
  PoseCorrections corrections;
  corrections.publish({pose(1, 0, 0, 0)});
  const PoseCorrections::Snapshot old = corrections.snapshot();
  corrections.publish({pose(2, 0, 0, 0)});
  EXPECT_NEAR(old.of(0).translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(corrections.snapshot().of(0).translation().x(), 2.0, 1e-12);
  EXPECT_NE(old.version, corrections.snapshot().version);
}

std::vector<VoxelMap::SurfacePoint> wall(float x, std::uint8_t grey, float weight) {
  std::vector<VoxelMap::SurfacePoint> points;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j) {
      VoxelMap::SurfacePoint p;
      p.position = Eigen::Vector3f(x, 0.01f * i + 0.005f, 0.01f * j + 0.005f);
      p.weight = weight;
      p.r = p.g = p.b = grey;
      points.push_back(p);
    }
  return points;
}

TEST(PointMerger, AlignedSubmapsOfOneWallGiveOneLayer) {
  PointMerger merger(0.01);
  // Two submaps saw the same wall at x = 1.003; the second one's frame is offset by 0.2 m,
  // which its pose takes back.
  merger.add(SurfaceCloud(wall(1.003f, 100, 1.0f)), Eigen::Isometry3d::Identity());
  merger.add(SurfaceCloud(wall(0.803f, 200, 3.0f)), pose(0.2, 0, 0, 0));
  EXPECT_EQ(merger.size(), 2500u);
  MapCloud cloud;
  merger.extract(cloud);
  ASSERT_EQ(cloud.size(), 2500u);
  for (const auto& p : cloud.points) {
    EXPECT_NEAR(p.x, 1.003f, 1e-5f);
    EXPECT_EQ(p.r, 175);  // weighted by what each submap fused: (100 + 3 * 200) / 4
  }
  EXPECT_EQ(cloud.width, 2500u);
}

TEST(PointMerger, MisalignedSubmapsStayTwoLayersAndOrderIsStable) {
  PointMerger merger(0.01);
  merger.add(SurfaceCloud(wall(1.003f, 100, 1.0f)), Eigen::Isometry3d::Identity());
  merger.add(SurfaceCloud(wall(1.003f, 100, 1.0f)), pose(0.05, 0, 0, 0));
  MapCloud first;
  merger.extract(first);
  EXPECT_EQ(first.size(), 5000u);
  PointMerger again(0.01);
  again.add(SurfaceCloud(wall(1.003f, 100, 1.0f)), Eigen::Isometry3d::Identity());
  again.add(SurfaceCloud(wall(1.003f, 100, 1.0f)), pose(0.05, 0, 0, 0));
  MapCloud second;
  again.extract(second);
  ASSERT_EQ(second.size(), first.size());
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i].x, second[i].x);
}

TEST(PointMerger, PointsOutsideTheKeyRangeAreLeftOut) {
  PointMerger merger(0.01);
  std::vector<VoxelMap::SurfacePoint> points = wall(1.0f, 10, 1.0f);
  points[0].position.x() = 1e9f;
  points[1].position.x() = std::nanf("");
  merger.add(SurfaceCloud(points), Eigen::Isometry3d::Identity());
  EXPECT_EQ(merger.size(), 2498u);
}

TEST(SurfaceCloud, KeepsPointsOfATenMetreSubmapTo0_15Millimetres) {
  std::vector<VoxelMap::SurfacePoint> points;
  std::mt19937 random(3);
  std::uniform_real_distribution<float> coordinate(-5.0f, 5.0f);
  for (int i = 0; i < 1000; ++i) {
    VoxelMap::SurfacePoint p;
    p.position = Eigen::Vector3f(coordinate(random), coordinate(random), 0.5f * coordinate(random));
    p.weight = 0.25f * static_cast<float>(i % 400);
    p.r = static_cast<std::uint8_t>(i % 256);
    p.g = 7;
    p.b = 200;
    points.push_back(p);
  }
  const SurfaceCloud cloud(points);
  ASSERT_EQ(cloud.size(), points.size());
  EXPECT_LE(cloud.memoryBytes(), points.size() * 12);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const VoxelMap::SurfacePoint p = cloud[i];
    EXPECT_LT((p.position - points[i].position).norm(), 1.5e-4f);
    EXPECT_NEAR(p.weight, std::max(points[i].weight, 1.0f / 16), 1.0f / 32);
    EXPECT_EQ(p.r, points[i].r);
    EXPECT_EQ(p.b, 200);
  }
  // One point far away would make the grid coarse: such a cloud is kept exactly.
  points[5].position.x() = 1e6f;
  const SurfaceCloud wide(points);
  ASSERT_EQ(wide.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_EQ(wide[i].position, points[i].position);
}

}  // namespace
}  // namespace rgbdmap
