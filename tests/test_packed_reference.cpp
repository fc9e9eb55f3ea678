// A place's alignment reference packed for a long run: half the memory, the same alignment, and
// packing what was expanded gives back the same bits (a session read and written again).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "rgbdmap/tracking/packed_reference.hpp"

namespace {

using namespace rgbdmap;

AlignmentReference randomReference() {
  AlignmentReference reference;
  reference.valid_pixels = 1234;
  reference.levels.resize(3);
  std::mt19937 random(7);
  std::uniform_real_distribution<float> lateral(-3.0f, 3.0f), depth(0.3f, 7.5f), grey(0, 255);
  for (std::size_t l = 1; l < 3; ++l) {  // level 0 unused, as when tracking starts at level 1
    reference.levels[l].camera.width = 320 >> (l - 1);
    reference.levels[l].camera.fx = 262.5f / static_cast<float>(1 << (l - 1));
    for (int i = 0; i < 500; ++i)
      reference.levels[l].points.emplace_back(lateral(random), lateral(random), depth(random),
                                              grey(random));
  }
  return reference;
}

TEST(PackedReference, KeepsEveryPointWithinATenthOfAMillimetreInHalfTheMemory) {
  const AlignmentReference reference = randomReference();
  const PackedReference packed = PackedReference::pack(reference);
  EXPECT_EQ(packed.points(), 1000u);
  EXPECT_EQ(sizeof(PackedReference::Point) * 2, sizeof(Eigen::Vector4f));
  AlignmentReference expanded;
  packed.expand(expanded);
  EXPECT_EQ(expanded.valid_pixels, 1234);
  ASSERT_EQ(expanded.levels.size(), 3u);
  EXPECT_TRUE(expanded.levels[0].points.empty());
  for (std::size_t l = 1; l < 3; ++l) {
    EXPECT_EQ(expanded.levels[l].camera.width, reference.levels[l].camera.width);
    EXPECT_EQ(expanded.levels[l].camera.fx, reference.levels[l].camera.fx);
    ASSERT_EQ(expanded.levels[l].points.size(), reference.levels[l].points.size());
    for (std::size_t i = 0; i < reference.levels[l].points.size(); ++i) {
      const Eigen::Vector4f d = expanded.levels[l].points[i] - reference.levels[l].points[i];
      EXPECT_LE(d.head<3>().cwiseAbs().maxCoeff(), 0.5f / 4096 + 1e-6f);
      EXPECT_LE(std::abs(d.w()), 0.5f / 256 + 1e-4f);
    }
  }
  // Packed again: the same bits.
  const PackedReference again = PackedReference::pack(expanded);
  for (std::size_t l = 0; l < 3; ++l) {
    ASSERT_EQ(again.levels[l].points.size(), packed.levels[l].points.size());
    for (std::size_t i = 0; i < packed.levels[l].points.size(); ++i) {
      const PackedReference::Point &a = again.levels[l].points[i], &b = packed.levels[l].points[i];
      EXPECT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z && a.intensity == b.intensity);
    }
  }
}

TEST(PackedReference, LeavesOutWhatItCannotHold) {
  AlignmentReference reference;
  reference.levels.resize(1);
  auto& points = reference.levels[0].points;
  points.emplace_back(0.1f, 0.2f, 1.0f, 100.0f);  // kept
  points.emplace_back(9.0f, 0.0f, 15.0f, 10.0f);  // x beyond 8 m
  points.emplace_back(0.0f, 0.0f, 17.0f, 10.0f);  // depth beyond 16 m
  points.emplace_back(0.0f, 0.0f, -0.5f, 10.0f);  // behind the camera
  points.emplace_back(0.0f, 0.0f, 2.0f, 300.0f);  // not a grey level
  points.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0f, 2.0f, 10.0f);
  const PackedReference packed = PackedReference::pack(reference);
  ASSERT_EQ(packed.points(), 1u);
  AlignmentReference expanded;
  packed.expand(expanded);
  EXPECT_TRUE(expanded.levels[0].points[0].isApprox(points[0], 1e-3f));
}

}  // namespace
