#include <gtest/gtest.h>

#include <random>
#include <set>

#include "rgbdmap/mapping/voxel_map.hpp"
#include "rgbdmap/runtime/checkpoint_writer.hpp"

namespace rgbdmap {
namespace {

PointBatch batchOf(const std::vector<Eigen::Vector3f>& points, float weight = 1.0f) {
  PointBatch b;
  for (const auto& p : points) {
    b.positions.push_back(p);
    b.colors.emplace_back(100, 150, 200);
    b.weights.push_back(weight);
  }
  return b;
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

TEST(VoxelMap, WeightedMeanOfPositionAndColour) {
  VoxelMap map(0.1);
  PointBatch b;
  b.positions = {{0.01f, 0.02f, 0.03f}, {0.05f, 0.06f, 0.07f}};
  b.colors = {{0, 0, 0}, {200, 100, 50}};
  b.weights = {1.0f, 3.0f};
  map.integrate(b);
  ASSERT_EQ(map.size(), 1u);
  const auto& v = map.voxels().front();
  EXPECT_NEAR(v.position.x(), (0.01f + 3 * 0.05f) / 4, 1e-6);
  EXPECT_NEAR(v.position.z(), (0.03f + 3 * 0.07f) / 4, 1e-6);
  EXPECT_NEAR(v.color.x(), 150.0f, 1e-4);
  EXPECT_FLOAT_EQ(v.weight, 4.0f);
  EXPECT_EQ(v.observations, 2u);
}

TEST(VoxelMap, OnePointPerVoxelAndRevisitsDoNotGrow) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 50000; ++i) points.emplace_back(u(rng), u(rng), 0.3f * u(rng));
  VoxelMap map(0.02);
  map.integrate(batchOf(points));
  const std::size_t size = map.size();
  map.integrate(batchOf(points));
  EXPECT_EQ(map.size(), size);
  MapCloud cloud;
  map.extract(cloud);
  ASSERT_EQ(cloud.size(), size);
  std::set<std::uint64_t> keys;
  for (const auto& p : cloud) {
    std::uint64_t key;
    ASSERT_TRUE(map.keyFor(p.getVector3fMap(), key));
    EXPECT_TRUE(keys.insert(key).second);
  }
}

TEST(VoxelMap, SceneLargerThanPclVoxelGridLimit) {
  // A 30 m x 30 m floor and a point 25 m up, at 5 mm voxels: 6000 x 5000 x 6000 cells, far past
  // the 2^31 PCL's VoxelGrid can index (it would return its input unfiltered). Every sample lies
  // in its own voxel, so the map must keep every one, once.
  VoxelMap map(0.005);
  std::vector<Eigen::Vector3f> points;
  const int n = 600;  // 600 x 600 samples 5 cm apart
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      points.emplace_back(-15.0f + 0.05f * i + 0.0025f, 0.0025f, -15.0f + 0.05f * j + 0.0025f);
  points.emplace_back(0.0025f, 25.0025f, 0.0025f);  // a 25 m tall outlier stretches the extent
  map.integrate(batchOf(points));
  EXPECT_EQ(map.size(), points.size());
  MapCloud cloud;
  map.extract(cloud);
  EXPECT_EQ(cloud.size(), points.size());
  EXPECT_EQ(map.rejectedPoints(), 0u);
}

TEST(VoxelMap, MinObservationsFiltersExtraction) {
  VoxelMap map(0.1);
  map.integrate(batchOf({{0.01f, 0.01f, 0.01f}, {0.02f, 0.02f, 0.02f}, {1.05f, 1.05f, 1.05f}}));
  MapCloud cloud;
  map.extract(cloud, 2);
  EXPECT_EQ(cloud.size(), 1u);
}

TEST(VoxelMap, PointCountIsWhatExtractWrites) {
  VoxelMap map(0.1, 2);
  map.integrate(batchOf({{0.01f, 0.01f, 0.01f}, {0.02f, 0.02f, 0.02f}, {1.05f, 1.05f, 1.05f}}));
  EXPECT_EQ(map.size(), 2u);
  EXPECT_EQ(map.pointCount(), 1u);
  MapCloud cloud;
  map.extract(cloud);
  EXPECT_EQ(cloud.size(), map.pointCount());
  map.integrate(batchOf({{1.06f, 1.06f, 1.06f}}));  // the second voxel's second point
  EXPECT_EQ(map.pointCount(), 2u);
}

TEST(VoxelMap, SameBatchesGiveTheSameCloudAcrossBlockBorders) {
  // Points on a slanted plane crossing many 8x8x8 blocks, both signs of every axis: each voxel
  // gets its own running mean, and extraction is deterministic (creation order).
  std::vector<Eigen::Vector3f> points;
  for (int i = -300; i < 300; ++i)
    for (int j = -300; j < 300; j += 3)
      points.emplace_back(0.0011f * i, 0.0013f * j, 0.3f * 0.0011f * i - 0.2f * 0.0013f * j);
  VoxelMap a(0.01), b(0.01);
  for (int pass = 0; pass < 2; ++pass) {
    a.integrate(batchOf(points));
    b.integrate(batchOf(points));
  }
  MapCloud ca, cb;
  a.extract(ca);
  b.extract(cb);
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t i = 0; i < ca.size(); ++i)
    EXPECT_EQ(ca[i].getVector3fMap(), cb[i].getVector3fMap());
  // One voxel per distinct key of the input, and each mean lies in its own voxel (a point per key).
  std::set<std::uint64_t> input_keys, output_keys;
  for (const auto& p : points) {
    std::uint64_t key;
    ASSERT_TRUE(a.keyFor(p, key));
    input_keys.insert(key);
  }
  for (const auto& p : ca) {
    std::uint64_t key;
    ASSERT_TRUE(a.keyFor(p.getVector3fMap(), key));
    output_keys.insert(key);
  }
  EXPECT_EQ(a.size(), input_keys.size());
  EXPECT_EQ(output_keys, input_keys);
}

}  // namespace
}  // namespace rgbdmap
