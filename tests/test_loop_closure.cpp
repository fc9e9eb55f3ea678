// The parts of loop closure that need no camera: the pose graph pulling a drifted loop shut,
// corrections applied to anchored poses.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

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
    edge.setMeasurement(step);
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
  closure.setMeasurement(loop.truth[0].inverse() * loop.truth[39]);
  closure.setSqrtInformation(10.0 * PoseGraph::Matrix6d::Identity());
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

// A second lap, closed at every keyframe against the first (already closed), optimised in a
// window of the newest keyframes: the first lap stays put, the second is pulled onto it as well
// as optimising everything would, and the problem solved stays the window's size (a patrol's
// graph grows with every keyframe; each loop must not cost more with it).
TEST(PoseGraph, AWindowOfTheNewestKeyframesIsPulledOntoTheOldLap) {
  const DriftedLoop loop = driftedLoop(40);
  auto twoLaps = [&](int first_free) {
    PoseGraph graph;
    // Lap 1: closed already (its edges as measured after correction: exact).
    for (const auto& p : loop.truth) graph.addNode(p);
    for (PoseGraph::Edge e : loop.steps) {
      e.setMeasurement(loop.truth[e.from].inverse() * loop.truth[e.to]);
      graph.addEdge(e);
    }
    // Lap 2 starts where lap 1 did and drifts like it.
    for (int i = 0; i < 40; ++i) {
      graph.addNode(i == 0 ? loop.truth[0] : graph.pose(39 + i) * loop.steps[i - 1].measurement());
      PoseGraph::Edge step;
      step.from = 39 + i;
      step.to = 40 + i;
      step.setMeasurement(i == 0 ? loop.truth[39].inverse() * loop.truth[0]
                                 : loop.steps[static_cast<std::size_t>(i - 1)].measurement());
      graph.addEdge(step);
      PoseGraph::Edge closure;  // lap 2's keyframe i is lap 1's keyframe i
      closure.from = i;
      closure.to = 40 + i;
      closure.setSqrtInformation(10.0 * PoseGraph::Matrix6d::Identity());
      closure.loop = true;
      graph.addEdge(closure);
    }
    std::vector<Eigen::Isometry3d> before;
    for (int i = 0; i < 40; ++i) before.push_back(graph.pose(i));
    EXPECT_TRUE(graph.optimise(100, first_free).usable);
    double lap1_moved = 0, lap2_error = 0;
    for (int i = 0; i < 40; ++i) {
      lap1_moved =
          std::max(lap1_moved, (graph.pose(i).translation() - before[i].translation()).norm());
      lap2_error = std::max(
          lap2_error, (graph.pose(40 + i).translation() - loop.truth[i].translation()).norm());
    }
    return std::make_pair(lap1_moved, lap2_error);
  };
  const double all_error = twoLaps(0).second;
  const auto [window_moved, window_error] = twoLaps(40);
  EXPECT_EQ(window_moved, 0.0);  // held
  EXPECT_LT(window_error, 0.01);
  EXPECT_LT(window_error, all_error + 0.002) << "optimising everything: " << all_error;
}

TEST(PoseGraph, RemovingTheLoopEdgeRestoresOdometry) {
  const DriftedLoop loop = driftedLoop(20);
  PoseGraph graph;
  for (const auto& p : loop.odometry) graph.addNode(p);
  for (const auto& e : loop.steps) graph.addEdge(e);
  PoseGraph::Edge closure;
  closure.from = 0;
  closure.to = 19;
  closure.setMeasurement(loop.truth[0].inverse() * loop.truth[19]);
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
  EXPECT_TRUE(root.triangularView<Eigen::StrictlyLower>().toDenseMatrix().isZero(0));
}

TEST(PoseGraph, AnEdgeKeepsItsWeightAsAnUpperTriangle) {
  PoseGraph::Edge edge;
  EXPECT_EQ(edge.sqrtInformation(), PoseGraph::Matrix6d::Identity());
  // Any square root is kept as the triangular one with the same information (a session from
  // before edges were stored this way holds another).
  PoseGraph::Matrix6d information;
  information << 400, 10, 0, 0, 5, 0, 10, 300, 0, 0, 0, 0, 0, 0, 100, 0, 0, 0, 0, 0, 0, 2500, 0, 0,
      5, 0, 0, 0, 2500, 30, 0, 0, 0, 0, 30, 900;
  Eigen::SelfAdjointEigenSolver<PoseGraph::Matrix6d> eig(information);
  const PoseGraph::Matrix6d general =
      eig.eigenvalues().cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose();
  edge.setSqrtInformation(general);
  const PoseGraph::Matrix6d kept = edge.sqrtInformation();
  EXPECT_TRUE(kept.triangularView<Eigen::StrictlyLower>().toDenseMatrix().isZero(0));
  EXPECT_LT((kept.transpose() * kept - information).norm(), 1e-3 * information.norm());
  // Set again from what it gives: the same bits (a session read and written again).
  PoseGraph::Edge again;
  again.setSqrtInformation(kept);
  EXPECT_EQ(again.sqrtInformation(), kept);
  const Eigen::Isometry3d motion = pose(0.3, -0.2, 1.5, 0.4);
  edge.setMeasurement(motion);
  EXPECT_TRUE(edge.measurement().isApprox(motion, 1e-15));
}

// A camera carried level down a 12 m corridor at 1.4 m, 60 keyframes, its odometry pitching
// 0.05 deg a step: it climbs 30 cm by the end. Each keyframe's view of the floor holds it down.
TEST(PoseGraph, FloorObservationsHoldHeightAndTilt) {
  const int n = 60;
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < n; ++i) truth.push_back(pose(0.2 * i, 0.0, 1.4, 0.02 * std::sin(0.3 * i)));
  PoseGraph graph;
  graph.addNode(truth[0]);
  Eigen::Isometry3d odometry = truth[0];
  const Eigen::AngleAxisd pitch(0.05 * M_PI / 180.0, Eigen::Vector3d::UnitY());
  for (int i = 1; i < n; ++i) {
    Eigen::Isometry3d step = truth[i - 1].inverse() * truth[i];
    step.linear() = pitch.toRotationMatrix() * step.linear();
    step.translation() = pitch * step.translation();
    odometry = odometry * step;
    graph.addNode(odometry);
    PoseGraph::Edge edge;
    edge.from = i - 1;
    edge.to = i;
    edge.setMeasurement(step);
    edge.setSqrtInformation(1000.0 * PoseGraph::Matrix6d::Identity());  // 1 mm, 1 mrad
    graph.addEdge(edge);
  }
  auto worst = [&](auto error) {
    double w = 0;
    for (int i = 0; i < n; ++i) w = std::max(w, error(graph.pose(i), truth[i]));
    return w;
  };
  auto height = [](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
    return std::abs(a.translation().z() - b.translation().z());
  };
  auto tilt = [](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
    return std::acos(std::min(1.0, (a.linear().transpose() * Eigen::Vector3d::UnitZ())
                                       .dot(b.linear().transpose() * Eigen::Vector3d::UnitZ())));
  };
  ASSERT_GT(worst(height), 0.2) << "the test's odometry should climb";
  ASSERT_GT(worst(tilt), 0.04);

  // The floor z = 0 as each camera sees it: n = R^T z, d = -z . t.
  graph.setWorldPlane(Eigen::Vector3d::UnitZ(), 0.0);
  for (int i = 0; i < n; i += 2) {  // every other keyframe sees it
    PoseGraph::PlaneObservation o;
    o.node = i;
    const Eigen::Vector3d normal = truth[i].linear().transpose() * Eigen::Vector3d::UnitZ();
    for (int k = 0; k < 3; ++k) o.normal[k] = static_cast<float>(normal[k]);
    o.distance = static_cast<float>(-truth[i].translation().z());
    graph.addPlaneObservation(o);
  }
  const PoseGraph::Checkpoint before = graph.checkpoint(0);
  ASSERT_TRUE(graph.optimise().usable);
  EXPECT_LT(worst(height), 0.005);
  EXPECT_LT(worst(tilt), 0.002);
  // Along the corridor and across it the floor says nothing: still the odometry's.
  EXPECT_LT(std::abs(graph.pose(n - 1).translation().x() - truth[n - 1].translation().x()), 0.02);

  // A rolled-back optimisation takes its observations back too.
  graph.rollBack(before);
  EXPECT_EQ(graph.planeObservations().size(), static_cast<std::size_t>(n / 2));
  graph.addPlaneObservation(PoseGraph::PlaneObservation{});
  graph.rollBack(before);
  EXPECT_EQ(graph.planeObservations().size(), static_cast<std::size_t>(n / 2));
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

}  // namespace
}  // namespace rgbdmap
