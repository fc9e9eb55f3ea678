// End to end through the real binary: `rgbdmap synth` a room, map it with ground-truth poses,
// score the map against the exact geometry with `rgbdmap evaluate`. The thresholds sit a little
// under what the mapper achieves (the measured numbers are printed and recorded as properties).
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "test_support.hpp"

namespace rgbdmap {
namespace {

// A room larger than the default (6 x 5 x 3 m): from the camera's circle the far walls are at
// up to ~4.5 m, beyond filter.max_depth (4 m), where the Kinect's depth noise (2.6 cm at 4 m) is
// well above the 1 cm voxel. 90 frames at 10 fps cover three quarters of a circle.
constexpr int kFrames = 90;
const std::string kLargeRoom = " --room 6x5x3 --fps 10 --frames " + std::to_string(kFrames);

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct MappingResult {
  double precision, recall, f_score, mean_mm, median_mm, p95_mm;
  long points;
};

// Maps the sequence in `sequence` with keyframe.every_n = every_n and scores the map.
MappingResult mapAndEvaluate(const std::string& sequence, const std::string& out, int every_n) {
  std::string output;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(test::run(test::binary() + " --source tum:" + sequence + " --out " + out +
                          ".pcd --rate max --set keyframe.every_n=" + std::to_string(every_n) +
                          " -q --no-render --stats " + out + "_stats.json",
                      &output),
            0)
      << output;
  std::cout << "mapping, every_n=" << every_n << ": " << secondsSince(start) << " s\n";

  EXPECT_EQ(test::run(test::binary() + " evaluate map " + out + ".pcd --scene " + sequence +
                          " --tau 0.01 --json " + out + "_score.json",
                      &output),
            0)
      << output;
  std::cout << output;
  const std::string json = test::readFile(out + "_score.json");
  MappingResult r{};
  r.precision = test::jsonNumber(json, "precision");
  r.recall = test::jsonNumber(json, "recall");
  r.f_score = test::jsonNumber(json, "f_score");
  r.mean_mm = test::jsonNumber(json, "mean_distance_mm");
  r.median_mm = test::jsonNumber(json, "median_distance_mm");
  r.p95_mm = test::jsonNumber(json, "p95_distance_mm");
  r.points = static_cast<long>(test::jsonNumber(test::readFile(out + "_stats.json"), "map_points"));
  const std::string prefix = "every_n_" + std::to_string(every_n) + "_";
  ::testing::Test::RecordProperty(prefix + "precision", std::to_string(r.precision));
  ::testing::Test::RecordProperty(prefix + "recall", std::to_string(r.recall));
  ::testing::Test::RecordProperty(prefix + "f_score", std::to_string(r.f_score));
  ::testing::Test::RecordProperty(prefix + "mean_mm", std::to_string(r.mean_mm));
  return r;
}

// One large-room sequence for the tests below (generating it is most of their time), written
// once for all of them (CTest runs each test in its own process).
class LargeRoom : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    room_ = new std::string(test::sharedSynthetic("room_6x5x3_90_frames", kLargeRoom));
  }
  static void TearDownTestSuite() {
    delete room_;
    room_ = nullptr;
  }
  void SetUp() override {
    dir_ = test::freshDir();
    std::filesystem::create_directory_symlink(*room_, dir_ + "/room");
  }
  static std::string* room_;
  std::string dir_;
};
std::string* LargeRoom::room_ = nullptr;

TEST_F(LargeRoom, MoreFramesMakeTheMapBetterNotThicker) {
  // Issue 11: fusing every frame must not lose to fusing every 10th (with points averaged where
  // they land it did: F 0.972 vs 0.993), and stays within millimetres of the exact surfaces.
  const MappingResult every = mapAndEvaluate(dir_ + "/room", dir_ + "/every1", 1);
  const MappingResult tenth = mapAndEvaluate(dir_ + "/room", dir_ + "/every10", 10);
  // Measured: every frame P 1.000, R 0.994, F 0.997, mean 0.45 mm; every 10th (9 keyframes)
  // P 1.000, R 0.85, F 0.92, mean 1.2 mm.
  EXPECT_GE(every.f_score, 0.98);
  EXPECT_GE(every.precision, 0.99);
  EXPECT_LT(every.mean_mm, 2.0);
  EXPECT_LT(every.p95_mm, 3.0);
  EXPECT_GE(every.f_score, tenth.f_score);
  EXPECT_GE(tenth.f_score, 0.9);
  EXPECT_LT(tenth.mean_mm, 2.0);
  // Every frame adds what the 10th frames never saw (measured 1.21x the points), but no layers
  // of noise (points averaged where they landed: ~3x).
  EXPECT_LE(every.points, tenth.points * 7 / 5);

  // The keyframe poses written beside the map are the interpolated ground truth; TUM's ATE
  // pairs them with the nearest 100 Hz sample (no interpolation), so a few millimetres remain.
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " evaluate trajectory --estimate " + dir_ +
                          "/every1_keyframes.txt --groundtruth " + dir_ +
                          "/room/groundtruth.txt --json " + dir_ + "/trajectory.json",
                      &output),
            0)
      << output;
  const std::string json = test::readFile(dir_ + "/trajectory.json");
  EXPECT_EQ(test::jsonNumber(json, "ate_pairs"), kFrames);
  EXPECT_LT(test::jsonNumber(json, "ate_rmse_m"), 0.004);
}

// Fusing every 10th frame scores lower against the surface all frames saw (above) because the
// other nine in ten saw more, not because fusion loses what it is given: the same path sampled
// at a tenth of the rate (so its reference is what those frames saw) maps to nearly all of it.
TEST(SparseViews, FusingFewFramesKeepsWhatTheySaw) {
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " synth --out " + dir +
                          "/room --room 6x5x3 --fps 1 --frames " + std::to_string(kFrames / 10),
                      &output),
            0)
      << output;
  const MappingResult sparse = mapAndEvaluate(dir + "/room", dir + "/map", 1);
  // Measured: P 1.000, R 0.990, F 0.995, mean 1.2 mm.
  EXPECT_GE(sparse.recall, 0.98);
  EXPECT_GE(sparse.f_score, 0.99);
  EXPECT_LT(sparse.mean_mm, 2.0);
}

// Writes the TUM list `name` of `first` and then of `second` (every timestamp `shift` seconds
// later, file names prefixed with the folder's name) to `out`: one sequence that goes over the
// same path twice, with the images of two recordings.
void writeTwoPasses(const std::string& root, const std::string& first, const std::string& second,
                    const std::string& name, const std::string& out_dir, double shift) {
  std::ofstream twice(out_dir + "/" + name);
  const bool images = name != "groundtruth.txt";
  int pass = 0;
  for (const std::string& folder : {first, second}) {
    std::ifstream in(root + "/" + folder + "/" + name);
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') {
        if (pass == 0) twice << line << "\n";
        continue;
      }
      std::istringstream fields(line);
      double stamp = 0;
      std::string rest;
      fields >> stamp;
      std::getline(fields, rest);
      if (images) rest = " " + folder + "/" + rest.substr(rest.find_first_not_of(' '));
      char moved[64];
      std::snprintf(moved, sizeof moved, "%.6f", stamp + pass * shift);
      twice << moved << rest << "\n";
    }
    ++pass;
  }
}

TEST_F(LargeRoom, ASecondPassWithFreshNoiseDoesNotGrowTheMap) {
  // Issue 11: revisiting a mapped area with fresh sensor noise adds at most 2% points. The same
  // path is rendered again with another noise seed and replayed after the first pass.
  std::string output;
  ASSERT_EQ(
      test::run(test::binary() + " synth --out " + dir_ + "/fresh --noise-seed 77" + kLargeRoom,
                &output),
      0)
      << output;
  namespace fs = std::filesystem;
  const std::string twice = dir_ + "/twice";
  fs::create_directory(twice);
  for (const char* folder : {"room", "fresh"})
    fs::create_directory_symlink(fs::absolute(dir_ + "/" + folder), twice + "/" + folder);
  for (const char* list : {"rgb.txt", "depth.txt", "groundtruth.txt"})
    writeTwoPasses(dir_, "room", "fresh", list, twice, 1000.0);
  fs::copy_file(dir_ + "/room/scene.yaml", twice + "/scene.yaml");
  fs::copy_file(dir_ + "/room/visible_surface.pcd", twice + "/visible_surface.pcd");

  const MappingResult once = mapAndEvaluate(dir_ + "/room", dir_ + "/once", 1);
  const MappingResult two = mapAndEvaluate(twice, dir_ + "/two", 1);
  std::cout << once.points << " points after one pass, " << two.points << " after two\n";
  EXPECT_EQ(test::jsonNumber(test::readFile(dir_ + "/two_stats.json"), "keyframes"), 2 * kFrames);
  EXPECT_GT(once.points, 100000);
  EXPECT_LE(two.points, once.points + once.points / 50);
  EXPECT_GE(two.f_score, once.f_score - 0.002);
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

}  // namespace
}  // namespace rgbdmap
