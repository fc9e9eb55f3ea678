// The OctoMap written with --octomap (issue 29), read back through liboctomap as a planner would:
// its occupied voxels lie on the synthetic room's exact surfaces, the space the camera looked
// through is free, and the inside of furniture and the space behind the walls never are.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <iostream>
#include <memory>

#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/mapping/free_space_map.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

TEST(FreeSpaceMap, MarksTheCellsARayCrossesUpToItsSurface) {
  OctomapOptions options;
  options.resolution = 0.1;
  options.ray_stride = 1;
  FreeSpaceMap free_space(options);
  CameraIntrinsics camera;
  camera.width = camera.height = 1;
  camera.cx = camera.cy = 0.0;
  const cv::Mat depth(1, 1, CV_32F, cv::Scalar(1.0));  // one ray, straight ahead to 1 m
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.05, 0.05, 0.05);  // a cell's centre
  free_space.carve(depth, camera, pose);
  std::vector<Eigen::Vector3i> cells;
  free_space.forEachFree([&cells](const Eigen::Vector3i& c) { cells.push_back(c); });
  // From the camera's cell to the one before the surface's (z in [1.0, 1.1) is the surface's).
  ASSERT_EQ(cells.size(), 10u);
  for (const Eigen::Vector3i& c : cells) {
    EXPECT_EQ(c.x(), 0);
    EXPECT_EQ(c.y(), 0);
    EXPECT_GE(c.z(), 0);
    EXPECT_LE(c.z(), 9);
  }
  free_space.carve(depth, camera, pose);  // seen again: no new cells
  EXPECT_EQ(free_space.freeCells(), 10u);
}

TEST(Octomap, OfTheSyntheticRoomHoldsItsSurfacesAndTheSpaceSeenThrough) {
  const std::string room =
      test::sharedSynthetic("room_6x5x3_90_frames", " --room 6x5x3 --fps 10 --frames 90");
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + room + " --out " + dir +
                          "/map.pcd --octomap " + dir +
                          "/map.bt --rate max --set keyframe.every_n=1 --set "
                          "filter.max_depth=5 -q --no-render",
                      &output),
            0)
      << output;
  EXPECT_NE(output.find("octomap: "), std::string::npos) << output;
  auto tree = std::make_unique<octomap::OcTree>(0.1);
  ASSERT_TRUE(tree->readBinary(dir + "/map.bt")) << dir + "/map.bt";
  const double r = tree->getResolution();
  EXPECT_DOUBLE_EQ(r, 0.05);
  const SyntheticGroundTruth truth = loadSyntheticGroundTruth(room);

  std::size_t occupied = 0, on_surface = 0, free_leaves = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    if (!tree->isNodeOccupied(*it)) {
      ++free_leaves;
      continue;
    }
    ++occupied;
    const octomap::point3d c = it.getCoordinate();
    // Within one voxel: the voxel's centre at most one voxel plus half its diagonal away.
    on_surface += truth.scene.distance(Eigen::Vector3d(c.x(), c.y(), c.z())) <= 1.87 * r;
  }
  const double share = static_cast<double>(on_surface) / static_cast<double>(occupied);
  std::cout << occupied << " occupied voxels, " << share << " within one voxel of a surface; "
            << free_leaves << " free leaves\n";
  EXPECT_GT(occupied, 5000u);
  EXPECT_GE(share, 0.95);

  // Every camera position was seen through (its rays start there); the space halfway from each
  // camera to the room's centre line too.
  const Trajectory cameras = Trajectory::load(dir + "/map_keyframes.txt");
  ASSERT_GT(cameras.size(), 10u);
  std::size_t free_cameras = 0;
  for (const StampedPose& p : cameras.poses()) {
    const Eigen::Vector3d t = p.pose.translation();
    const octomap::OcTreeNode* node = tree->search(t.x(), t.y(), t.z());
    free_cameras += node && !tree->isNodeOccupied(node);
  }
  EXPECT_GE(free_cameras, cameras.size() * 95 / 100) << free_cameras << " of " << cameras.size();

  // Never free: inside a box (furniture is solid) and behind the walls.
  std::size_t checked = 0, wrongly_free = 0;
  for (const ScenePrimitive& primitive : truth.scene.primitives()) {
    if (primitive.kind != ScenePrimitive::Kind::kBox) continue;
    const Eigen::Vector3d centre = 0.5 * (primitive.min + primitive.max);
    const octomap::OcTreeNode* node = tree->search(centre.x(), centre.y(), centre.z());
    ++checked;
    wrongly_free += node && !tree->isNodeOccupied(node);
  }
  for (const Eigen::Vector3d& behind :
       {Eigen::Vector3d(3.3, 0, 1.5), Eigen::Vector3d(-3.3, 0, 1.5), Eigen::Vector3d(0, 2.8, 1.5),
        Eigen::Vector3d(0, -2.8, 1.5), Eigen::Vector3d(0, 0, -0.3), Eigen::Vector3d(0, 0, 3.3)}) {
    const octomap::OcTreeNode* node = tree->search(behind.x(), behind.y(), behind.z());
    ++checked;
    wrongly_free += node && !tree->isNodeOccupied(node);
  }
  EXPECT_GT(checked, 6u);
  EXPECT_EQ(wrongly_free, 0u);
}

}  // namespace
}  // namespace rgbdmap
