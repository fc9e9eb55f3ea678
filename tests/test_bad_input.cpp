// Bad input never crashes: one clear message naming the file (and line), and
// either the frame is skipped and counted or the run stops with a non-zero
// exit.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>

#include "rgbdmap/capture/tum_sequence.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;
using test::kXyz;

struct Outcome {
  int exit_code;
  std::string output;
};

Outcome map(const std::string& folder, const std::string& out_dir, const std::string& extra = "") {
  Outcome o;
  o.exit_code = test::run(test::binary() + " --source tum:" + folder + " --out " + out_dir +
                              "/map.pcd --rate max -q --no-render --stats " + out_dir +
                              "/stats.json " + extra,
                          &o.output);
  return o;
}

// Replaces line `number` (1-based) of a text file.
void replaceLine(const std::string& path, std::size_t number, const std::string& text) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_LE(number, lines.size());
  lines[number - 1] = text;
  std::ofstream out(path);
  for (const auto& l : lines) out << l << "\n";
}

std::string statsOf(const std::string& dir) { return test::readFile(dir + "/stats.json"); }

TEST(BadInput, MissingFolder) {
  const std::string dir = test::freshDir();
  const Outcome o = map(dir + "/nowhere", dir);
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find(dir + "/nowhere: no such folder"), std::string::npos) << o.output;
}

TEST(BadInput, MissingListFile) {
  const std::string dir = test::freshDir();
  const std::string seq = test::copySequence(test::tumDir(kXyz), dir + "/seq");
  fs::remove(seq + "/depth.txt");
  const Outcome o = map(seq, dir);
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find(seq + "/depth.txt: missing"), std::string::npos) << o.output;
}

TEST(BadInput, MalformedListLine) {
  const std::string dir = test::freshDir();
  const std::string seq = test::copySequence(test::tumDir(kXyz), dir + "/seq");
  replaceLine(seq + "/rgb.txt", 7, "1305031102.2753x6 rgb/1305031102.275326.png");
  Outcome o = map(seq, dir);
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find(seq + "/rgb.txt:7: timestamp '1305031102.2753x6' is not a number"),
            std::string::npos)
      << o.output;

  replaceLine(seq + "/rgb.txt", 7, "1305031102.275326");
  o = map(seq, dir);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.output.find(seq + "/rgb.txt:7: expected 'timestamp filename'"), std::string::npos)
      << o.output;
}

TEST(BadInput, TimestampsOutOfOrder) {
  const std::string dir = test::freshDir();
  const std::string seq = test::copySequence(test::tumDir(kXyz), dir + "/seq");
  replaceLine(seq + "/depth.txt", 8, "1305031102.100000 depth/1305031102.295279.png");
  const Outcome o = map(seq, dir);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.output.find(seq + "/depth.txt:8: timestamp 1305031102.100000 is not after"),
            std::string::npos)
      << o.output;
}

TEST(BadInput, NanOrNonUnitPose) {
  const std::string dir = test::freshDir();
  const std::string seq = test::copySequence(test::tumDir(kXyz), dir + "/seq");
  replaceLine(seq + "/groundtruth.txt", 355,
              "1305031102.1758 1.3405 nan 1.6575 0.6574 0.6126 -0.2949 -0.3248");
  Outcome o = map(seq, dir);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.output.find(seq + "/groundtruth.txt:355: ty is nan (not finite)"), std::string::npos)
      << o.output;

  replaceLine(seq + "/groundtruth.txt", 355,
              "1305031102.1758 1.3405 0.6266 1.6575 0.9 0.6126 -0.2949 -0.3248");
  o = map(seq, dir);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.output.find(seq + "/groundtruth.txt:355: quaternion norm"), std::string::npos)
      << o.output;
}

// Image problems skip the one frame (counted) and the rest of the sequence is
// still mapped.
class BadImage : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::freshDir();
    seq_ = dir_ + "/seq";
    fs::create_directories(seq_);
    for (const char* list : {"rgb.txt", "depth.txt", "groundtruth.txt"})
      fs::copy_file(test::tumDir(kXyz) + "/" + list, seq_ + "/" + list);
    fs::copy(test::tumDir(kXyz) + "/rgb", seq_ + "/rgb");
    fs::copy(test::tumDir(kXyz) + "/depth", seq_ + "/depth");
  }
  void expectOneSkipped(const std::string& what) {
    const Outcome o = map(seq_, dir_);
    EXPECT_EQ(o.exit_code, 0) << o.output;
    EXPECT_NE(o.output.find(what), std::string::npos) << o.output;
    const std::string stats = statsOf(dir_);
    EXPECT_NE(stats.find("\"frames_skipped\": 1,"), std::string::npos) << stats;
    EXPECT_NE(stats.find("\"frames_captured\": 31,"), std::string::npos) << stats;
    EXPECT_GT(test::loadMap(dir_ + "/map.pcd").size(), 10000u);
  }
  std::string dir_, seq_;
};

TEST_F(BadImage, ListedImageDoesNotExist) {
  fs::remove(seq_ + "/rgb/1305031102.311267.png");  // rgb.txt line 8
  expectOneSkipped(seq_ + "/rgb.txt:8: " + seq_ + "/rgb/1305031102.311267.png: cannot open image");
}

TEST_F(BadImage, TruncatedPng) {
  const std::string path = seq_ + "/depth/1305031102.295279.png";  // depth.txt line 8
  fs::resize_file(path, fs::file_size(path) / 3);
  expectOneSkipped(seq_ + "/depth.txt:8: " + path + ": cannot decode image");
}

TEST_F(BadImage, DepthOfTheWrongSize) {
  const std::string path = seq_ + "/depth/1305031102.295279.png";
  cv::Mat small(240, 320, CV_16UC1, cv::Scalar(5000));
  ASSERT_TRUE(cv::imwrite(path, small));
  expectOneSkipped(seq_ + "/depth.txt:8: " + path + ": depth is 320x240 but colour");
}

TEST_F(BadImage, NotAnImageAtAll) {
  // Must not silently reuse the previous frame's colour.
  std::ofstream(seq_ + "/rgb/1305031102.311267.png") << "this is not a picture";
  expectOneSkipped(seq_ + "/rgb.txt:8: " + seq_ +
                   "/rgb/1305031102.311267.png: not an image format OpenCV can read");
}

TEST_F(BadImage, ColourWhereDepthShouldBe) {
  fs::copy_file(seq_ + "/rgb/1305031102.311267.png", seq_ + "/depth/1305031102.295279.png",
                fs::copy_options::overwrite_existing);
  expectOneSkipped(
      "depth must be a 16-bit single-channel image (this PNG has 8-bit 3-channel pixels)");
}

// Datasets converted to the TUM layout (7-Scenes, ...) often ship JPEG colour: any format OpenCV
// reads is colour. Depth must stay lossless 16-bit: PNG or TIFF.
TEST_F(BadImage, JpegColourAndTiffDepthMap) {
  const TumSequence sequence(seq_);
  std::ofstream rgb(seq_ + "/rgb.txt"), depth(seq_ + "/depth.txt");
  rgb << std::fixed << std::setprecision(6);
  depth << std::fixed << std::setprecision(6);
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const std::string jpg = fs::path(sequence[i].rgb_path).stem().string() + ".jpg";
    ASSERT_TRUE(cv::imwrite(seq_ + "/rgb/" + jpg, cv::imread(sequence[i].rgb_path)));
    rgb << sequence[i].rgb_time << " rgb/" << jpg << "\n";
    std::string depth_file = "depth/" + fs::path(sequence[i].depth_path).filename().string();
    if (i % 2 == 0) {  // every other depth image as TIFF
      depth_file = "depth/" + fs::path(sequence[i].depth_path).stem().string() + ".tiff";
      ASSERT_TRUE(cv::imwrite(seq_ + "/" + depth_file,
                              cv::imread(sequence[i].depth_path, cv::IMREAD_UNCHANGED)));
    }
    depth << sequence[i].depth_time << " " << depth_file << "\n";
  }
  rgb.close();
  depth.close();
  const Outcome o = map(seq_, dir_);
  EXPECT_EQ(o.exit_code, 0) << o.output;
  const std::string stats = statsOf(dir_);
  EXPECT_NE(stats.find("\"frames_skipped\": 0,"), std::string::npos) << stats;
  EXPECT_GT(test::loadMap(dir_ + "/map.pcd").size(), 10000u);
}

TEST_F(BadImage, JpegDepthIsRefusedByName) {
  const std::string path = seq_ + "/depth/1305031102.295279.png";  // depth.txt line 8
  ASSERT_TRUE(cv::imwrite(seq_ + "/depth.jpg", cv::imread(path)));
  fs::rename(seq_ + "/depth.jpg", path);
  expectOneSkipped(seq_ + "/depth.txt:8: " + path +
                   ": depth must be a 16-bit PNG or TIFF image (this is JPEG)");
}

// A run that maps no frame has failed: exit 1, saying why and how many frames each reason hit.
TEST_F(BadImage, NothingMappedExitsNonZeroWithTheReasons) {
  const TumSequence sequence(seq_);
  const std::size_t frames = sequence.size();
  fs::remove_all(seq_ + "/depth");
  fs::create_directory(seq_ + "/depth");
  const Outcome o = map(seq_, dir_);
  EXPECT_EQ(o.exit_code, 1) << o.output;
  EXPECT_NE(o.output.find("nothing mapped: none of the " + std::to_string(frames) +
                          " frames could be used:\n  " + std::to_string(frames) +
                          " frames: depth image: cannot open image (first: " + seq_ +
                          "/depth.txt:" + std::to_string(sequence[0].depth_line) + ": "),
            std::string::npos)
      << o.output;
}

TEST_F(BadImage, MostFramesUnusedIsSaidAtTheEnd) {
  const TumSequence sequence(seq_);
  const std::size_t removed = sequence.size() - 5;
  for (std::size_t i = 5; i < sequence.size(); ++i) fs::remove(sequence[i].rgb_path);
  const Outcome o = map(seq_, dir_);
  EXPECT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("most frames were not mapped: " + std::to_string(removed) + " of " +
                          std::to_string(sequence.size()) + " could not be used:\n  " +
                          std::to_string(removed) + " frames: colour image: cannot open image"),
            std::string::npos)
      << o.output;
  EXPECT_GT(test::loadMap(dir_ + "/map.pcd").size(), 10000u);
}

TEST(BadInput, UnknownConfigKeyAndBadRate) {
  const std::string dir = test::freshDir();
  Outcome o = map(test::tumDir(kXyz), dir, "--set map.voxelsize=0.01");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.output.find("unknown config key 'map.voxelsize'"), std::string::npos) << o.output;
  o.exit_code = test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --out " + dir +
                              "/map.pcd --rate fast -q",
                          &o.output);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.output.find("--rate: replay.rate: 'fast' is not a number"), std::string::npos)
      << o.output;
  EXPECT_FALSE(fs::exists(dir + "/map.pcd"));
}

TEST(BadInput, UnwritableOutputIsReportedNotCrashed) {
  std::string output;
  const int code =
      test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) +
                    " --out /proc/rgbdmap-no-such-dir/map.pcd --rate max -q --no-render",
                &output);
  // Refused before mapping starts, naming the folder.
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("--out /proc/rgbdmap-no-such-dir/map.pcd: cannot create the folder "
                        "/proc/rgbdmap-no-such-dir"),
            std::string::npos)
      << output;
  EXPECT_EQ(output.find("source:"), std::string::npos) << "the source was opened: " << output;
}

TEST(BadInput, GarbageMapFilesAreNamedNotCrashed) {
  const std::string dir = test::freshDir();
  const std::string garbage = dir + "/garbage.pcd";
  {
    std::ofstream out(garbage, std::ios::binary);
    for (int i = 0; i < 3000; ++i) out.put(static_cast<char>((i * 7919 + 13) % 251));
  }
  const std::string truncated = dir + "/truncated.pcd";
  {
    std::ofstream out(truncated, std::ios::binary);
    out << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 100\nHEIGHT "
           "1\nPOINTS 100\nDATA binary\nabc";
  }
  // Found by fuzz/fuzz_map_file: a NUL inside the DATA line made PCL's header reader throw,
  // and `render` died of the uncaught exception.
  const std::string nul_in_header = dir + "/nul_in_header.pcd";
  {
    std::ofstream out(nul_in_header, std::ios::binary);
    const std::string header =
        "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 2\n"
        "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA";
    out << header << '\0' << "ascii\n0 0 1 4.2e6\n1 2 3 0\n";
  }
  // Found by fuzz/fuzz_map_file: 1-byte y, z, rgb fields made PCL's conversion read past the
  // data (ASan: heap-buffer-overflow).
  const std::string narrow_fields = dir + "/narrow_fields.pcd";
  std::ofstream(narrow_fields, std::ios::binary)
      << "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 "
         "0 0 0\nPOINTS 2\nDATA ascii\n0 1 2 3\n1 2 3 0\n";
  for (const std::string& path : {garbage, truncated, nul_in_header, narrow_fields}) {
    std::string output;
    const int code =
        test::run(test::binary() + " render " + path + " --out " + dir + "/x.png", &output);
    EXPECT_NE(code, 0) << output;
    EXPECT_LT(code, 128) << "crashed: " << output;
    EXPECT_NE(output.find(path + ": "), std::string::npos) << output;
    EXPECT_FALSE(fs::exists(dir + "/x.png"));
  }
}

TEST(BadInput, SynthRefusesARoomSizeItCannotFurnish) {
  const std::string dir = test::freshDir();
  std::string output;
  EXPECT_NE(
      test::run(test::binary() + " synth --frames 2 --out " + dir + "/room --room 6x2x3", &output),
      0);
  EXPECT_NE(output.find("--room"), std::string::npos) << output;
}

TEST(BadInput, SynthNamesABadSceneFile) {
  const std::string dir = test::freshDir();
  std::string output;
  EXPECT_NE(test::run(test::binary() + " synth --frames 2 --out " + dir + "/room --scene " + dir +
                          "/missing.yaml",
                      &output),
            0);
  EXPECT_NE(output.find(dir + "/missing.yaml"), std::string::npos) << output;
}

TEST(BadInput, SynthRefusesADepthCameraItCannotRead) {
  const std::string dir = test::freshDir();
  // Too few numbers, and a depth camera half a metre from the colour one.
  for (const char* value : {"0.025,0,0", "0.5,0,0,0,0,0"}) {
    std::string output;
    EXPECT_EQ(test::run(test::binary() + " synth --frames 2 --out " + dir +
                            "/room --depth-camera " + value,
                        &output),
              2);
    EXPECT_NE(output.find(std::string("--depth-camera '") + value + "': expected X,Y,Z,RX,RY,RZ"),
              std::string::npos)
        << output;
    EXPECT_FALSE(fs::exists(dir + "/room/rgb.txt"));
  }
  // A depth camera's focal length no lens has.
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " synth --frames 2 --out " + dir +
                          "/room --depth-camera 0.025,0,0,0,0,0 --depth-focal 50",
                      &output),
            2);
  EXPECT_NE(output.find("--depth-focal 50"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir + "/room/rgb.txt"));
}

}  // namespace
}  // namespace rgbdmap
