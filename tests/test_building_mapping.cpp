// End to end through the real binary on a building: `rgbdmap synth --building` a small floor
// with its tour, map an excerpt of it (ground-truth poses), score it with `rgbdmap evaluate` as
// a room is scored. The thresholds sit a little under what the mapper achieves.
#include <gtest/gtest.h>

#include <iostream>
#include <string>

#include "test_support.hpp"

namespace rgbdmap {
namespace {

TEST(BuildingMapping, AnExcerptOfATourMapsItsWallsDoorsAndFurniture) {
  // 12 x 8 m, seed 2; 200 frames at 10 fps: 20 s of the tour, along the corridor, through the
  // first door and round the room.
  const std::string sequence = test::sharedSynthetic(
      "building_12x8", " --building 12x8 --seed 2 --path tour --frames 200 --fps 10");
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + sequence + " --out " + dir +
                          "/map.pcd --rate max -q --no-render --stats " + dir + "/stats.json",
                      &output),
            0)
      << output;
  ASSERT_EQ(test::run(test::binary() + " evaluate map " + dir + "/map.pcd --scene " + sequence +
                          " --json " + dir + "/score.json",
                      &output),
            0)
      << output;
  std::cout << output;
  const std::string json = test::readFile(dir + "/score.json");
  const double precision = test::jsonNumber(json, "precision");
  const double recall = test::jsonNumber(json, "recall");
  ::testing::Test::RecordProperty("precision", std::to_string(precision));
  ::testing::Test::RecordProperty("recall", std::to_string(recall));
  // Measured: P 0.9987, R 0.66 with the default keyframes (every 10th frame); 300 frames of it
  // R 0.71, and R 0.83 with every frame fused. What the map misses is surface the sensor saw only
  // at 60 to 78 degrees from its normal, mostly the floor far ahead: with --max-incidence 60 the
  // same excerpt scores R 0.983.
  EXPECT_GE(precision, 0.99);
  EXPECT_GE(recall, 0.6);
  EXPECT_LT(test::jsonNumber(json, "mean_distance_mm"), 3.0);
  // The sequence says what it is: a tour of a building, the scene a floor with walls.
  EXPECT_NE(test::readFile(sequence + "/synthetic.yaml").find("path: tour"), std::string::npos);
  EXPECT_NE(test::readFile(sequence + "/scene.yaml").find("kind: wall"), std::string::npos);
}

}  // namespace
}  // namespace rgbdmap
