// End to end through the real binary: `rgbdmap synth` a room, map it with ground-truth poses,
// score the map against the exact geometry with `rgbdmap evaluate`. The thresholds sit a little
// under what the mapper achieves (the measured numbers are printed and recorded as properties).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "test_support.hpp"

namespace rgbdmap {
namespace {

constexpr int kFrames = 150;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct MappingResult {
  double precision, recall, f_score, mean_mm, median_mm, p95_mm;
};

// Generates the sequence, maps it with keyframe.every_n = every_n and scores the map.
MappingResult synthMapEvaluate(const std::string& dir, int every_n) {
  std::string output;
  auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(test::run(test::binary() + " synth --out " + dir + "/room --frames " +
                          std::to_string(kFrames),
                      &output),
            0)
      << output;
  std::cout << "synth " << kFrames << " frames: " << secondsSince(start) << " s\n";

  start = std::chrono::steady_clock::now();
  EXPECT_EQ(test::run(test::binary() + " --source tum:" + dir + "/room --out " + dir +
                          "/map.pcd --rate max --set keyframe.every_n=" + std::to_string(every_n) +
                          " -q --no-render",
                      &output),
            0)
      << output;
  std::cout << "mapping, every_n=" << every_n << ": " << secondsSince(start) << " s\n";

  EXPECT_EQ(test::run(test::binary() + " evaluate map " + dir + "/map.pcd --scene " + dir +
                          "/room --tau 0.01 --json " + dir + "/score.json",
                      &output),
            0)
      << output;
  std::cout << output;
  const std::string json = test::readFile(dir + "/score.json");
  MappingResult r{};
  r.precision = test::jsonNumber(json, "precision");
  r.recall = test::jsonNumber(json, "recall");
  r.f_score = test::jsonNumber(json, "f_score");
  r.mean_mm = test::jsonNumber(json, "mean_distance_mm");
  r.median_mm = test::jsonNumber(json, "median_distance_mm");
  r.p95_mm = test::jsonNumber(json, "p95_distance_mm");
  const std::string prefix = "every_n_" + std::to_string(every_n) + "_";
  ::testing::Test::RecordProperty(prefix + "precision", std::to_string(r.precision));
  ::testing::Test::RecordProperty(prefix + "recall", std::to_string(r.recall));
  ::testing::Test::RecordProperty(prefix + "f_score", std::to_string(r.f_score));
  ::testing::Test::RecordProperty(prefix + "mean_mm", std::to_string(r.mean_mm));
  return r;
}

TEST(SyntheticMapping, EveryFrameMapsTheVisibleSurfaceWithinMillimetres) {
  const std::string dir = test::freshDir();
  const MappingResult r = synthMapEvaluate(dir, 1);
  // Measured: P 1.000, R 0.998, F 0.999, mean 0.73 mm (issue 3 asks F >= 0.99, mean <= 2 mm).
  EXPECT_LT(r.median_mm, 1.5);
  EXPECT_LT(r.mean_mm, 1.5);
  EXPECT_LT(r.p95_mm, 3.0);
  EXPECT_GE(r.precision, 0.99);
  EXPECT_GE(r.recall, 0.98);
  EXPECT_GE(r.f_score, 0.985);

  // The keyframe poses written beside the map are the interpolated ground truth; TUM's ATE
  // pairs them with the nearest 100 Hz sample (no interpolation), so a few millimetres remain.
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " evaluate trajectory --estimate " + dir +
                          "/map_keyframes.txt --groundtruth " + dir +
                          "/room/groundtruth.txt --json " + dir + "/trajectory.json",
                      &output),
            0)
      << output;
  std::cout << output;
  const std::string json = test::readFile(dir + "/trajectory.json");
  EXPECT_EQ(test::jsonNumber(json, "ate_pairs"), kFrames);
  EXPECT_LT(test::jsonNumber(json, "ate_rmse_m"), 0.004);
  EXPECT_LT(test::jsonNumber(json, "rpe_rot_rmse_deg"), 0.5);
}

TEST(SyntheticMapping, EveryTenthFrameStillCoversMostOfTheSurface) {
  const std::string dir = test::freshDir();
  const MappingResult r = synthMapEvaluate(dir, 10);
  // Measured: P 1.000, R 0.952, F 0.976, mean 0.68 mm (issue 3 asks F >= 0.95).
  EXPECT_LT(r.median_mm, 1.5);
  EXPECT_LT(r.mean_mm, 1.5);
  EXPECT_GE(r.precision, 0.99);
  EXPECT_GE(r.recall, 0.92);
  EXPECT_GE(r.f_score, 0.955);
}

// Writes `list` (a TUM list: comment lines, then "timestamp rest") to `out` twice: as it is, then
// with every timestamp moved `shift` seconds later, so the same frames are read a second time.
void writeTwice(const std::string& list, const std::string& out, double shift) {
  std::ifstream in(list);
  std::ofstream twice(out);
  std::string line, comments, entries, shifted;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      comments += line + "\n";
      continue;
    }
    std::istringstream fields(line);
    double stamp = 0;
    std::string rest;
    fields >> stamp;
    std::getline(fields, rest);
    char moved[64];
    std::snprintf(moved, sizeof moved, "%.6f", stamp + shift);
    entries += line + "\n";
    shifted += moved + rest + "\n";
  }
  twice << comments << entries << shifted;
}

long mapPoints(const std::string& stats_json) {
  return static_cast<long>(test::jsonNumber(test::readFile(stats_json), "map_points"));
}

TEST(SyntheticMapping, ASecondPassOverTheSameFramesDoesNotGrowTheMap) {
  // Issue 3, target 5: revisiting what is mapped adds no points. The same frames (same images,
  // same poses, 1000 s later) are replayed after themselves; the map must keep its size.
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " synth --frames 40 --out " + dir + "/once", &output), 0)
      << output;
  namespace fs = std::filesystem;
  fs::create_directory(dir + "/twice");
  for (const char* folder : {"rgb", "depth"})
    fs::create_directory_symlink(fs::absolute(dir + "/once/" + folder), dir + "/twice/" + folder);
  for (const char* list : {"rgb.txt", "depth.txt", "groundtruth.txt"})
    writeTwice(dir + "/once/" + list, dir + "/twice/" + list, 1000.0);

  for (const int every_n : {1, 5}) {
    long points[2] = {0, 0};
    int i = 0;
    for (const char* sequence : {"once", "twice"}) {
      const std::string stats = dir + "/" + sequence + ".json";
      ASSERT_EQ(test::run(test::binary() + " --source tum:" + dir + "/" + sequence + " --out " +
                              dir + "/" + sequence + ".pcd --rate max -q --no-render --stats " +
                              stats + " --set keyframe.every_n=" + std::to_string(every_n),
                          &output),
                0)
          << output;
      EXPECT_EQ(test::jsonNumber(test::readFile(stats), "keyframes"), (i + 1) * 40 / every_n);
      points[i++] = mapPoints(stats);
    }
    std::cout << "every " << every_n << ": " << points[0] << " points after one pass, " << points[1]
              << " after two\n";
    EXPECT_GT(points[0], 100000);
    EXPECT_LE(std::abs(points[1] - points[0]), 10) << "every_n=" << every_n;
  }
}

TEST(SyntheticMapping, NoiseFreeDepthGivesAnAlmostExactMap) {
  // Without sensor noise the only errors left are the mapper's own (voxel averaging at edges,
  // filtering): a regression in back-projection or pose handling shows up here first.
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(
      test::run(test::binary() + " synth --no-noise --frames 60 --out " + dir + "/room", &output),
      0)
      << output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + dir + "/room --out " + dir +
                          "/map.pcd --rate max --set keyframe.every_n=5 -q --no-render",
                      &output),
            0)
      << output;
  ASSERT_EQ(test::run(test::binary() + " evaluate map " + dir + "/map.pcd --scene " + dir +
                          "/room --json " + dir + "/score.json",
                      &output),
            0)
      << output;
  std::cout << output;
  const std::string json = test::readFile(dir + "/score.json");
  EXPECT_LT(test::jsonNumber(json, "median_distance_mm"), 0.5);
  EXPECT_LT(test::jsonNumber(json, "mean_distance_mm"), 0.5);
  EXPECT_GE(test::jsonNumber(json, "precision"), 0.99);
  EXPECT_GE(test::jsonNumber(json, "recall"), 0.9);
}

TEST(SyntheticMapping, SynthNamesABadSceneFile) {
  const std::string dir = test::freshDir();
  std::string output;
  EXPECT_NE(test::run(test::binary() + " synth --frames 2 --out " + dir + "/room --scene " + dir +
                          "/missing.yaml",
                      &output),
            0);
  EXPECT_NE(output.find(dir + "/missing.yaml"), std::string::npos) << output;
}

}  // namespace
}  // namespace rgbdmap
