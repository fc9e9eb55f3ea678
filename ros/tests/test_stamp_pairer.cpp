// The streaming pairer gives the pairs TUM's associate() gives on the whole lists.
#include <gtest/gtest.h>

#include <random>

#include "rgbdmap/capture/association.hpp"
#include "rgbdmap/ros/stamp_pairer.hpp"

namespace rgbdmap {
namespace {

// Two 30 Hz streams with jitter, offsets and gaps, interleaved by arrival as a bag or a
// subscriber sees them; every pair out of the pairer must be one of associate()'s.
TEST(StampPairer, StreamingGivesTheWholeListPairs) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.006, 0.006), offset(-0.015, 0.015);
  std::bernoulli_distribution gap(0.05);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> color, depth;
    const double shift = offset(rng);
    for (int i = 0; i < 300; ++i) {
      if (!gap(rng)) color.push_back(100 + i / 30.0 + jitter(rng));
      if (!gap(rng)) depth.push_back(100 + i / 30.0 + shift + jitter(rng));
    }
    const auto expected = associate(color, depth, 0.02);

    StampPairer<std::size_t> pairer(0.02);
    std::vector<std::pair<std::size_t, std::size_t>> got;
    StampPairer<std::size_t>::Pair pair;
    std::size_t c = 0, d = 0;
    while (c < color.size() || d < depth.size()) {
      if (d >= depth.size() || (c < color.size() && color[c] <= depth[d])) {
        pairer.addColor(color[c], c);
        ++c;
      } else {
        pairer.addDepth(depth[d], d);
        ++d;
      }
      while (pairer.next(pair)) got.emplace_back(pair.color, pair.depth);
    }
    while (pairer.next(pair, true)) got.emplace_back(pair.color, pair.depth);
    EXPECT_EQ(got, expected) << "trial " << trial;
    EXPECT_EQ(pairer.pending(), 0u);
    EXPECT_EQ(pairer.unmatched(), color.size() + depth.size() - 2 * expected.size());
  }
}

TEST(StampPairer, OneSilentStreamHoldsABoundedWindow) {
  StampPairer<int> pairer(0.02, 16);
  StampPairer<int>::Pair pair;
  for (int i = 0; i < 1000; ++i) {
    pairer.addColor(i / 30.0, i);
    EXPECT_FALSE(pairer.next(pair));
  }
  EXPECT_LE(pairer.pending(), 16u);
  EXPECT_EQ(pairer.unmatched(), 1000u - pairer.pending());
}

}  // namespace
}  // namespace rgbdmap
