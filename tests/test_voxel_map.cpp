// The TSDF voxel map and its projective integration on images of exact planes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <iostream>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "rgbdmap/mapping/block_store.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/mesh_extractor.hpp"
#include "rgbdmap/mapping/tsdf_integrator.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {
namespace {

CameraIntrinsics smallCamera() {
  CameraIntrinsics c;
  c.width = 160;
  c.height = 120;
  c.fx = c.fy = 150.0;
  c.cx = 79.5;
  c.cy = 59.5;
  return c;
}

// Depth image of the plane z = distance + slope * x (camera frame), with Gaussian noise of
// `sigma` metres drawn from `seed` (0: exact).
cv::Mat planeDepth(const CameraIntrinsics& c, double distance, double slope, double sigma,
                   unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(sigma));
  cv::Mat depth(c.height, c.width, CV_32FC1);
  for (int v = 0; v < c.height; ++v)
    for (int u = 0; u < c.width; ++u) {
      const double z = distance / (1.0 - slope * (u - c.cx) / c.fx);
      depth.at<float>(v, u) = static_cast<float>(z) + (sigma > 0 ? noise(rng) : 0.0f);
    }
  return depth;
}

cv::Mat grey(const CameraIntrinsics& c) {
  return cv::Mat(c.height, c.width, CV_8UC3, cv::Scalar(90, 120, 150));
}

TsdfIntegrator integratorFor(const CameraIntrinsics& c) {
  TsdfIntegrator t;
  t.camera = c;
  return t;
}

MapCloud extractOf(const VoxelMap& map) {
  MapCloud cloud;
  map.extract(cloud);
  return cloud;
}

TEST(VoxelMap, KeysRoundTripIncludingNegativeCoordinates) {
  VoxelMap map(0.01);
  for (const Eigen::Vector3f& p :
       {Eigen::Vector3f(0.005f, 0.005f, 0.005f), Eigen::Vector3f(-0.005f, -1.234f, 7.5f),
        Eigen::Vector3f(-10000.0f, 10000.0f, -0.0f)}) {
    std::uint64_t key;
    ASSERT_TRUE(map.keyFor(p, key));
    const Eigen::Vector3i v = VoxelMap::unpack(key);
    for (int axis = 0; axis < 3; ++axis)
      EXPECT_EQ(v[axis], static_cast<int>(std::floor(p[axis] / 0.01f)));
  }
  std::uint64_t key;
  EXPECT_FALSE(map.keyFor(Eigen::Vector3f(20000.0f, 0, 0), key));  // beyond ±2^20 voxels
  EXPECT_FALSE(map.keyFor(Eigen::Vector3f(std::nanf(""), 0, 0), key));
}

TEST(VoxelMap, AnExactPlaneGivesOneLayerOfPointsOnThePlane) {
  const CameraIntrinsics c = smallCamera();
  VoxelMap map(0.01);
  integratorFor(c).integrate(planeDepth(c, 2.0, 0.0, 0.0, 0), grey(c),
                             Eigen::Isometry3d::Identity(), map);
  const MapCloud cloud = extractOf(map);
  ASSERT_GT(cloud.size(), 1000u);
  EXPECT_EQ(cloud.size(), map.pointCount());
  std::set<std::pair<int, int>> columns;
  for (const auto& p : cloud) {
    EXPECT_NEAR(p.z, 2.0, 0.001);
    EXPECT_TRUE(columns
                    .insert({static_cast<int>(std::floor(p.x / 0.01)),
                             static_cast<int>(std::floor(p.y / 0.01))})
                    .second)
        << "two points over one voxel column at " << p;
    EXPECT_EQ(p.r, 150);
    EXPECT_EQ(p.b, 90);
  }
}

TEST(VoxelMap, NoisyViewsOfAFarPlaneConvergeInsteadOfThickening) {
  // At 3.5 m the depth noise (2 cm) is twice the voxel: points averaged where they land would
  // spread over several voxels; along the line of sight the views average into one layer.
  const CameraIntrinsics c = smallCamera();
  const double sigma = 0.0012 + 0.0019 * (3.5 - 0.4) * (3.5 - 0.4);
  VoxelMap map(0.01);
  TsdfIntegrator tsdf = integratorFor(c);
  std::size_t after_first = 0;
  for (unsigned frame = 1; frame <= 12; ++frame) {
    tsdf.integrate(planeDepth(c, 3.5, 0.3, sigma, frame), grey(c), Eigen::Isometry3d::Identity(),
                   map);
    if (frame == 1) after_first = map.pointCount();
  }
  const MapCloud cloud = extractOf(map);
  EXPECT_EQ(cloud.size(), map.pointCount());
  EXPECT_LE(cloud.size(), after_first + after_first / 50) << "more views made the map thicker";
  double sum = 0.0;
  for (const auto& p : cloud) {
    const double plane_z = 3.5 + 0.3 * p.x;  // the plane z = 3.5 + 0.3 x
    sum += std::abs(p.z - plane_z);
  }
  const double mean = sum / static_cast<double>(cloud.size());
  std::cout << cloud.size() << " points (" << after_first << " after one view), mean |dz| "
            << mean * 1000 << " mm\n";
  // One view is off by 0.8 sigma (16 mm) on average; 12 averaged views, by about sigma / sqrt(12)
  // along the line of sight (measured 4.7 mm).
  EXPECT_LT(mean, sigma / 3.0);
}

TEST(VoxelMap, PointCountIsWhatExtractWritesAcrossBlockBorders) {
  // A tilted plane through the origin crosses blocks with negative and positive coordinates.
  const CameraIntrinsics c = smallCamera();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(-0.03, 0.02, -1.0);
  VoxelMap a(0.01), b(0.01);
  TsdfIntegrator tsdf = integratorFor(c);
  for (unsigned frame = 1; frame <= 4; ++frame) {
    const cv::Mat depth = planeDepth(c, 1.0, -0.5, 0.002, frame);
    tsdf.integrate(depth, grey(c), pose, a);
    tsdf.integrate(depth, grey(c), pose, b);
    EXPECT_EQ(a.pointCount(), extractOf(a).size());
  }
  // The same frames give the same cloud, point for point.
  const MapCloud ca = extractOf(a), cb = extractOf(b);
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t i = 0; i < ca.size(); ++i)
    EXPECT_EQ(ca[i].getVector3fMap(), cb[i].getVector3fMap());
}

TEST(VoxelMap, MinObservationsLeavesOutVoxelsSeenOnce) {
  const CameraIntrinsics c = smallCamera();
  VoxelMap once(0.01, 2);
  TsdfIntegrator tsdf = integratorFor(c);
  tsdf.integrate(planeDepth(c, 2.0, 0.0, 0.0, 0), grey(c), Eigen::Isometry3d::Identity(), once);
  EXPECT_EQ(once.pointCount(), 0u);
  EXPECT_TRUE(extractOf(once).empty());
  tsdf.integrate(planeDepth(c, 2.0, 0.0, 0.0, 0), grey(c), Eigen::Isometry3d::Identity(), once);
  EXPECT_GT(once.pointCount(), 1000u);
}

TEST(VoxelMap, MissingDepthAllocatesNothing) {
  const CameraIntrinsics c = smallCamera();
  VoxelMap map(0.01);
  cv::Mat depth(c.height, c.width, CV_32FC1, cv::Scalar(0.0f));
  depth.at<float>(10, 10) = std::nanf("");
  integratorFor(c).integrate(depth, grey(c), Eigen::Isometry3d::Identity(), map);
  EXPECT_EQ(map.blockCount(), 0u);
  EXPECT_EQ(map.pointCount(), 0u);
}

// Idle blocks away from every surface go: free space in front of it, and the far side of a wall
// that a distant view's wide band (7.8 cm at 4 m) reached. Every point of the surface stays, and a
// view measuring there again allocates what it needs anew.
TEST(VoxelMap, IdleBlocksInFrontOfOrBehindASurfaceGoAndTheSurfaceStays) {
  const CameraIntrinsics c = smallCamera();
  const double distance = 4.0;
  const double sigma = 0.0012 + 0.0019 * (distance - 0.4) * (distance - 0.4);
  VoxelMap map(0.01);
  TsdfIntegrator tsdf = integratorFor(c);
  for (unsigned frame = 1; frame <= 6; ++frame)
    tsdf.integrate(planeDepth(c, distance, 0.2, sigma, frame), grey(c),
                   Eigen::Isometry3d::Identity(), map);
  const MapCloud before = extractOf(map);
  const std::size_t blocks = map.blockCount();
  std::size_t behind = 0;  // blocks whose every observed voxel is 2 voxels or more behind
  for (std::uint32_t i = 0; i < map.blockSlots(); ++i) {
    const VoxelMap::Block& b = map.block(i);
    if (std::all_of(b.voxels.begin(), b.voxels.end(),
                    [](const VoxelMap::Voxel& v) { return !v.observed() || v.sdf() <= -0.02f; }))
      ++behind;
  }
  ASSERT_GT(behind, 0u);
  // Not idle yet: nothing goes.
  EXPECT_EQ(map.pruneAwayFromSurfaces(10, 0.02f), 0u);
  for (int i = 0; i < 12; ++i) {  // views elsewhere
    map.beginIntegration();
    map.finishIntegration();
  }
  const std::size_t freed = map.pruneAwayFromSurfaces(10, 0.02f);
  std::cout << freed << " of " << blocks << " blocks freed, " << behind << " of them behind\n";
  EXPECT_GE(freed, behind);
  EXPECT_EQ(map.blockCount(), blocks - freed);
  // Every point stays. A point next to a freed block is moved onto the zero level along a
  // one-sided gradient instead of a central one: by a fraction of a voxel.
  const MapCloud after = extractOf(map);
  ASSERT_EQ(after.size(), before.size());
  std::size_t moved = 0;
  float farthest = 0.0f;
  for (std::size_t i = 0; i < after.size(); ++i) {
    const float d = (after[i].getVector3fMap() - before[i].getVector3fMap()).norm();
    if (d > 0.0f) ++moved;
    farthest = std::max(farthest, d);
  }
  std::cout << moved << " of " << after.size() << " points moved, by at most " << farthest * 1000
            << " mm\n";
  EXPECT_LT(moved, after.size() / 10);
  EXPECT_LT(farthest, 0.005f);
  EXPECT_EQ(map.pointCount(), after.size());
}

// A map emptied for a re-fusion pass fuses exactly as a new one does, in the memory it had; what
// a smaller map no longer needs is handed back.
TEST(VoxelMap, AClearedMapFusesAsANewOneInTheMemoryItHad) {
  const CameraIntrinsics c = smallCamera();
  TsdfIntegrator tsdf = integratorFor(c);
  VoxelMap reused(0.01), fresh(0.01);
  for (unsigned frame = 1; frame <= 3; ++frame)
    tsdf.integrate(planeDepth(c, 3.0, 0.4, 0.01, frame), grey(c), Eigen::Isometry3d::Identity(),
                   reused);
  const std::size_t memory = reused.memoryBytes();
  reused.clear();
  EXPECT_EQ(reused.blockCount(), 0u);
  EXPECT_EQ(reused.pointCount(), 0u);
  EXPECT_EQ(reused.memoryBytes(), memory);
  const cv::Mat near = planeDepth(c, 1.0, 0.0, 0.0, 0);
  tsdf.integrate(near, grey(c), Eigen::Isometry3d::Identity(), reused);
  tsdf.integrate(near, grey(c), Eigen::Isometry3d::Identity(), fresh);
  const MapCloud a = extractOf(reused), b = extractOf(fresh);
  ASSERT_GT(a.size(), 1000u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ(a[i].getVector3fMap(), b[i].getVector3fMap());
  EXPECT_EQ(reused.blockCount(), fresh.blockCount());
  reused.releaseUnused();
  EXPECT_LT(reused.memoryBytes(), memory);
}

// The points of a map as a sorted list: maps with blocks on disk write them in another order.
std::vector<std::tuple<float, float, float, int>> sortedPoints(const VoxelMap& map) {
  std::vector<std::tuple<float, float, float, int>> points;
  for (const pcl::PointXYZRGB& p : extractOf(map))
    points.emplace_back(p.x, p.y, p.z, (p.r << 16) | (p.g << 8) | p.b);
  std::sort(points.begin(), points.end());
  return points;
}

// How many points one list has that the other has not (both sorted), printing a few.
std::size_t pointsApart(const std::vector<std::tuple<float, float, float, int>>& a,
                        const std::vector<std::tuple<float, float, float, int>>& b) {
  std::vector<std::tuple<float, float, float, int>> apart;
  std::set_symmetric_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(apart));
  for (std::size_t i = 0; i < std::min<std::size_t>(apart.size(), 6); ++i)
    std::cout << "  apart: " << std::get<0>(apart[i]) << " " << std::get<1>(apart[i]) << " "
              << std::get<2>(apart[i]) << "\n";
  return apart.size();
}

// A camera 2 m from a wall (z = 2) that walks 8 m along it and back, 3 noisy frames a step,
// fused into `map`; `after` is called after each frame.
void walkAlongAWall(VoxelMap& map, const std::function<void()>& after) {
  const CameraIntrinsics c = smallCamera();
  TsdfIntegrator tsdf = integratorFor(c);
  unsigned seed = 1;
  for (int step = 0; step <= 16; ++step) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation().x() = 0.5 * (step <= 8 ? step : 16 - step);
    for (int frame = 0; frame < 3; ++frame) {
      tsdf.integrate(planeDepth(c, 2.0, 0.3, 0.004, seed++), grey(c), pose, map);
      after();
    }
  }
}

// Beyond its memory a map moves the blocks the camera left to disk; they come back when it
// returns, and every map written (points, count, mesh) is the one a map without a limit gives.
TEST(VoxelMap, BlocksBeyondItsMemoryGoToDiskAndTheMapWrittenStaysTheSame) {
  VoxelMap whole(0.01), limited(0.01);
  // Blocks away from surfaces are freed as the Mapper frees them, on disk or not.
  std::size_t pruned = 0;
  const auto prune = [&pruned](VoxelMap& map) {
    if (map.integrations() % 4 == 0) pruned += map.pruneAwayFromSurfaces(6, 0.02f);
  };
  walkAlongAWall(whole, [&] { prune(whole); });
  const std::size_t pruned_whole = std::exchange(pruned, 0);
  const std::size_t all_blocks = whole.blockCount();
  const std::size_t max_blocks = all_blocks / 4;
  std::size_t most_in_memory = 0, stored = 0;
  walkAlongAWall(limited, [&] {
    prune(limited);
    stored += limited.keepWithin(max_blocks, 3);
    most_in_memory = std::max(most_in_memory, limited.blockCount());
  });
  std::cout << all_blocks << " blocks; at most " << most_in_memory << " in memory, "
            << limited.storedBlocks().size() << " on disk at the end ("
            << limited.storedBlocks().storedBytes() / 1024 << " KB), " << stored
            << " moved to disk in all; " << pruned_whole << " freed\n";
  ASSERT_GT(pruned_whole, 0u);
  EXPECT_EQ(pruned, pruned_whole);
  ASSERT_GT(limited.storedBlocks().size(), 0u);
  EXPECT_GT(stored, limited.storedBlocks().size());  // some came back as the camera returned
  // Blocks updated in the last 3 views stay (what the camera sees, and sees through): the limit
  // is exceeded by them, not by the walk's length.
  EXPECT_LT(most_in_memory, all_blocks / 2);
  EXPECT_LT(limited.memoryBytes(), whole.memoryBytes() * 6 / 10);
  EXPECT_EQ(limited.blockCount() + limited.storedBlocks().size(), all_blocks);

  const auto expected = sortedPoints(whole);
  ASSERT_GT(expected.size(), 10000u);
  EXPECT_EQ(pointsApart(sortedPoints(limited), expected), 0u);
  EXPECT_EQ(limited.pointCount(), expected.size());
  EXPECT_EQ(whole.pointCount(), expected.size());
  const TriangleMesh a = extractMesh(whole), b = extractMesh(limited);
  ASSERT_GT(a.triangles.size(), 10000u);
  EXPECT_EQ(b.triangles.size(), a.triangles.size());
  EXPECT_EQ(b.vertices.size(), a.vertices.size());

  // A region fused again (Mapper's region pass) replaces the map's blocks there, on disk or not,
  // the same way.
  VoxelMap region_whole(0.01), region_limited(0.01);
  // Not convex (as a region of footprint cells need not be): a block outside it can border it
  // on two sides.
  const auto in = [](const Eigen::Vector3i& block) {
    return (block.x() >= 10 && block.x() < 30) ||
           (block.x() >= 30 && block.x() < 40 && block.y() >= 0);
  };
  region_whole.limitTo(in);
  region_limited.limitTo(in);
  const CameraIntrinsics c = smallCamera();
  TsdfIntegrator tsdf = integratorFor(c);
  for (int step = 0; step < 8; ++step) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0.4 * step, 0.0, 0.01);  // the wall 1 cm nearer
    const cv::Mat depth = planeDepth(c, 2.0, 0.3, 0.004, 100 + step);
    tsdf.integrate(depth, grey(c), pose, region_whole);
    tsdf.integrate(depth, grey(c), pose, region_limited);
    region_limited.keepWithin(all_blocks / 20, 1);
  }
  ASSERT_GT(region_limited.storedBlocks().size(), 0u);
  whole.replaceRegion(region_whole, in);
  limited.replaceRegion(region_limited, in);
  const auto replaced = sortedPoints(whole);
  EXPECT_GT(pointsApart(replaced, expected), 1000u);
  EXPECT_EQ(pointsApart(sortedPoints(limited), replaced), 0u);
  EXPECT_EQ(limited.pointCount(), replaced.size());
  EXPECT_EQ(whole.pointCount(), replaced.size());

  // Emptied for a whole pass: what was on disk goes too.
  limited.clear();
  EXPECT_EQ(limited.storedBlocks().size(), 0u);
  EXPECT_EQ(limited.pointCount(), 0u);
  EXPECT_TRUE(extractOf(limited).empty());
}

// Blocks stored, taken back and stored again, as a camera walking to and fro makes them: the file
// is written again without what was taken back before it grows past its bound, and every block
// reads back as it was last stored.
TEST(BlockStore, AFileOfBlocksTakenBackIsRewrittenAndEveryStoredBlockReadsBack) {
  const std::uint64_t compact_above = 256 * 1024;
  BlockStore store(compact_above);
  std::mt19937 rng(3);
  std::map<std::uint64_t, BlockStore::Voxels> expected;
  std::uint64_t largest_file = 0;
  std::string error;
  for (int round = 0; round < 40; ++round) {
    for (std::uint64_t key = 0; key < 64; ++key) {
      if (round > 0 && key % 3 != static_cast<std::uint64_t>(round) % 3) continue;
      BlockStore::Voxels voxels{};
      for (int i = 0; i < BlockStore::kVoxels; ++i) {
        if (rng() % 4 == 0) continue;  // never observed
        voxels[i].set(static_cast<float>(static_cast<int>(rng() % 200) - 100) * 1e-4f,
                      1.0f + static_cast<float>(rng() % 10));
        voxels[i].r = static_cast<std::uint8_t>(rng());
        voxels[i].observations = static_cast<std::uint8_t>(1 + rng() % 20);
      }
      store.erase(key);  // taken back into memory, then stored again
      ASSERT_TRUE(store.put(key, voxels, static_cast<std::uint32_t>(key), round, error)) << error;
      expected[key] = voxels;
      largest_file = std::max(largest_file, store.fileBytes());
    }
  }
  std::cout << store.size() << " blocks, " << store.storedBytes() / 1024 << " KB stored; the file "
            << "grew to " << largest_file / 1024 << " KB at most, now " << store.fileBytes() / 1024
            << " KB\n";
  EXPECT_EQ(store.size(), 64u);
  // Rewritten at least once (40 rounds wrote some 13 times what is stored), and never far past
  // its bound (one block's bytes).
  EXPECT_LT(largest_file, compact_above + 3 * store.storedBytes() + 8192);
  std::vector<std::uint8_t> scratch;
  for (const auto& [key, voxels] : expected) {
    const BlockStore::Stored* stored = store.find(key);
    ASSERT_NE(stored, nullptr);
    EXPECT_EQ(stored->surface_points, key);
    BlockStore::Voxels back;
    ASSERT_TRUE(store.read(*stored, back, scratch, error)) << error;
    EXPECT_EQ(std::memcmp(back.data(), voxels.data(), sizeof(voxels)), 0) << "block " << key;
  }
}

}  // namespace
}  // namespace rgbdmap
