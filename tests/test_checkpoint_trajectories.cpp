// Trajectories streamed to their files at checkpoints (TrajectoryStream): appended without loop
// closure, rewritten with the latest corrections with it; poses recorded on one thread while
// another writes; a failed write keeps the poses for the next checkpoint.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

#include "rgbdmap/map_files/trajectory_stream.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

Eigen::Isometry3d poseAt(double x) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, 0.5 * x, 1.0);
  pose.linear() = Eigen::AngleAxisd(0.1 * x, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return pose;
}

TEST(CheckpointTrajectories, AppendsWhatWasRecordedSinceTheLastCheckpoint) {
  const std::string path = test::freshDir() + "/t.txt";
  { std::ofstream(path) << "left by an earlier run\n"; }
  TrajectoryStream stream(path, nullptr);
  std::string error;
  for (int i = 0; i < 3; ++i) stream.record(100.0 + i, poseAt(i), -1);
  ASSERT_TRUE(stream.persist(error)) << error;
  ASSERT_EQ(stream.load().size(), 3u);  // what an earlier run left is gone
  for (int i = 3; i < 5; ++i) stream.record(100.0 + i, poseAt(i), -1);
  ASSERT_TRUE(stream.persist(error)) << error;
  const Trajectory t = stream.load();
  ASSERT_EQ(t.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_DOUBLE_EQ(t[i].timestamp, 100.0 + i);
    EXPECT_TRUE(t[i].pose.isApprox(poseAt(i), 1e-6)) << i;
  }
  EXPECT_FALSE(fs::exists(path + ".anchored"));
}

TEST(CheckpointTrajectories, WithLoopClosureTheFileTakesTheLatestCorrections) {
  const std::string path = test::freshDir() + "/t.txt";
  PoseCorrections corrections;
  {
    TrajectoryStream stream(path, &corrections);
    std::string error;
    stream.record(1.0, poseAt(1), 0);
    stream.record(2.0, poseAt(2), 1);
    stream.record(3.0, poseAt(3), -1);
    ASSERT_TRUE(stream.persist(error)) << error;
    EXPECT_TRUE(stream.load()[1].pose.isApprox(poseAt(2), 1e-6));
    // A loop closes: keyframe 1 moves 10 cm along x; the poses anchored to it move with it.
    PoseCorrections::Table table(2, Eigen::Isometry3d::Identity());
    table[1].translation() = Eigen::Vector3d(0.1, 0, 0);
    corrections.publish(table);
    stream.record(4.0, poseAt(4), 1);
    ASSERT_TRUE(stream.persist(error)) << error;
    const Trajectory t = stream.load();
    ASSERT_EQ(t.size(), 4u);
    EXPECT_TRUE(t[0].pose.isApprox(poseAt(1), 1e-6));
    EXPECT_TRUE(t[1].pose.isApprox(table[1] * poseAt(2), 1e-6));
    EXPECT_TRUE(t[2].pose.isApprox(poseAt(3), 1e-6));  // no anchor: never moved
    EXPECT_TRUE(t[3].pose.isApprox(table[1] * poseAt(4), 1e-6));
    EXPECT_TRUE(fs::exists(path + ".anchored"));
  }
  EXPECT_FALSE(fs::exists(path + ".anchored"));  // the spool goes with the stream
  EXPECT_EQ(Trajectory::load(path).size(), 4u);
}

TEST(CheckpointTrajectories, AFailedWriteIsReportedAndLosesNoPose) {
  // The folder is a regular file: the write fails for root too (ENOTDIR).
  const std::string folder = test::freshDir() + "/maps";
  { std::ofstream(folder) << "not a folder\n"; }
  const std::string path = folder + "/t.txt";
  TrajectoryStream stream(path, nullptr);
  stream.record(1.0, poseAt(1), -1);
  std::string error;
  EXPECT_FALSE(stream.persist(error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  fs::remove(folder);
  fs::create_directory(folder);
  stream.record(2.0, poseAt(2), -1);
  ASSERT_TRUE(stream.persist(error)) << error;
  EXPECT_EQ(stream.load().size(), 2u);
}

TEST(CheckpointTrajectories, PosesRecordedWhileAnotherThreadWritesAreAllKeptInOrder) {
  const std::string path = test::freshDir() + "/t.txt";
  TrajectoryStream stream(path, nullptr);
  std::atomic<bool> done{false};
  std::thread tracking([&] {
    for (int i = 0; i < 2000; ++i) stream.record(i * 0.01, poseAt(i * 0.001), -1);
    done.store(true);
  });
  std::string error;
  while (!done.load()) ASSERT_TRUE(stream.persist(error)) << error;
  tracking.join();
  ASSERT_TRUE(stream.persist(error)) << error;
  const Trajectory t = stream.load();
  ASSERT_EQ(t.size(), 2000u);
  for (std::size_t i = 1; i < t.size(); ++i) ASSERT_LT(t[i - 1].timestamp, t[i].timestamp);
}

}  // namespace
}  // namespace rgbdmap
