// A TUM folder played as a Kinect v1 through the whole stack, without hardware: `record --format
// fakenect` writes the folder as a fakenect dump (raw disparity), Debian's fakenect libfreenect
// replays it, the project's OpenNI2 Kinect driver (drivers/openni2_freenect) converts and
// registers it, and rgbdmap reads it as `--source openni2`.

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "rgbdmap/capture/accelerometer_log.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/drivers/kinect_accelerometer.hpp"
#include "rgbdmap/drivers/kinect_v1_model.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

using test::kXyz;
const std::string kFakenectDir = "/usr/lib/x86_64-linux-gnu/fakenect";

bool kinectDriverBuilt() {
  return fs::exists(fs::path(test::binary()).parent_path() / "openni2/OpenNI2/Drivers" /
                    "libKinectV1Device.so.0");
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}

bool waitForLog(const std::string& path, const std::string& text, double timeout_s) {
  return test::waitUntil([&] { return occurrences(test::readFile(path), text) > 0; }, timeout_s);
}

// rgbdmap with libfreenect replaced by fakenect playing `dump`.
std::vector<std::string> withFakenect(const std::string& dump, std::vector<std::string> args) {
  std::vector<std::string> command = {"/usr/bin/env", "FAKENECT_PATH=" + dump,
                                      "LD_LIBRARY_PATH=" + kFakenectDir, test::binary()};
  command.insert(command.end(), args.begin(), args.end());
  return command;
}

// The folder as a fakenect dump, once per test.
std::string writeDump(const std::string& dir) {
  const std::string dump = dir + "/dump";
  std::string output;
  const int code =
      test::run(test::binary() + " record --format fakenect --source tum:" + test::tumDir(kXyz) +
                    " --out " + dump,
                &output);
  EXPECT_EQ(code, 0) << output;
  return dump;
}

// Stretches a dump's timing by `factor` (fakenect paces playback by the seconds in each file
// name), so a reader on a loaded machine or in a sanitizer build keeps up with the "camera".
void slowDown(const std::string& dump, double factor) {
  std::vector<std::string> names;
  {
    std::ifstream index(dump + "/INDEX.txt");
    for (std::string line; std::getline(index, line);) names.push_back(line);
  }
  ASSERT_FALSE(names.empty());
  const double first = std::stod(names.front().substr(2));
  std::ofstream index(dump + "/INDEX.txt", std::ios::trunc);
  for (const std::string& name : names) {
    const std::size_t seconds_end = name.find('-', 2);
    const double seconds = first + (std::stod(name.substr(2, seconds_end - 2)) - first) * factor;
    char stretched[64];
    std::snprintf(stretched, sizeof stretched, "%.6f", seconds);
    const std::string renamed = name.substr(0, 2) + stretched + name.substr(seconds_end);
    fs::rename(dump + "/" + name, dump + "/" + renamed);
    index << renamed << "\n";
  }
}

class OpenNI2Freenect : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kFakenectDir + "/libfreenect.so.0.5"))
      GTEST_SKIP() << "fakenect is not installed (libfreenect0.5)";
    if (!kinectDriverBuilt()) GTEST_SKIP() << "the OpenNI2 Kinect driver is not built";
  }
};

TEST_F(OpenNI2Freenect, DumpHoldsEveryFrameAsRawDisparityAndRgb) {
  const std::string dump = writeDump(test::freshDir());
  std::ifstream index(dump + "/INDEX.txt");
  std::vector<std::string> files;
  for (std::string line; std::getline(index, line);) files.push_back(line);
  const TumSequence sequence(test::tumDir(kXyz));
  const AccelerometerLog log = AccelerometerLog::load(test::tumDir(kXyz) + "/accelerometer.txt");
  // Per frame: the accelerometer's record (fr1/xyz has one for every frame), depth, colour.
  ASSERT_EQ(files.size(), 3 * sequence.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::size_t frame = i / 3;
    EXPECT_EQ(files[i][0], "adr"[i % 3]) << files[i];
    const std::string data = test::readFile(dump + "/" + files[i]);
    if (i % 3 == 0) {
      // libfreenect's raw tilt state: counts of 1/819 g giving the folder's up.
      ASSERT_EQ(data.size(), sizeof(FakenectTiltState)) << files[i];
      FakenectTiltState state;
      std::memcpy(&state, data.data(), sizeof state);
      const KinectAcceleration a = KinectAcceleration::fromCounts(
          state.accelerometer_x, state.accelerometer_y, state.accelerometer_z);
      const auto up = AccelerometerLog::upFromSample({a.x, a.y, a.z});
      const auto truth = log.upAt(sequence[frame].rgb_time);
      ASSERT_TRUE(up && truth) << files[i];
      EXPECT_LT(std::acos(std::min(1.0, up->dot(*truth))) * 180 / M_PI, 0.2) << files[i];
      continue;
    }
    const std::string header = i % 3 == 1 ? "P5 640 480 65535\n" : "P6 640 480 255\n";
    ASSERT_EQ(data.substr(0, header.size()), header) << files[i];
    EXPECT_EQ(data.size(), header.size() + 640u * 480u * (i % 3 == 1 ? 2u : 3u)) << files[i];
  }
}

// Frames delivered through fakenect -> driver -> OpenNI2 -> rgbdmap match the folder: colour
// exactly, depth within the disparity quantisation; the end of the dump is reported as an
// unplug; the accelerometer comes through the driver's device property. Recorded back as a TUM
// folder by `rgbdmap record --source openni2`.
TEST_F(OpenNI2Freenect, FramesThroughTheKinectDriverMatchTheFolder) {
#ifdef __SANITIZE_THREAD__
  GTEST_SKIP() << "under ThreadSanitizer fakenect delivers no frame to the driver within the read "
                  "timeout; release and ASan builds run this test";
#endif
  const std::string dir = test::freshDir();
  const std::string dump = writeDump(dir);
  slowDown(dump, 4.0);  // ~7.5 frames/s: a recorder writing PNGs keeps up
  test::Process record(withFakenect(dump, {"record", "--source", "openni2", "--out", dir + "/rec"}),
                       dir + "/record.log");
  ASSERT_TRUE(waitForLog(dir + "/record.log", "camera stopped delivering frames", 120))
      << test::readFile(dir + "/record.log");
  record.signal(SIGINT);
  ASSERT_EQ(record.wait(120), 0) << test::readFile(dir + "/record.log");
  const std::string log = test::readFile(dir + "/record.log");
  EXPECT_NE(log.find("openni2:freenect:0"), std::string::npos) << log;
  EXPECT_NE(log.find("OpenNI2 reports the device disconnected"), std::string::npos) << log;

  const TumSequence folder(test::tumDir(kXyz));
  const TumSequence recorded(dir + "/rec");
  // A live camera: a loaded machine may still drop some; most come through.
  ASSERT_GE(recorded.size(), folder.size() / 2) << log;
  std::vector<cv::Mat> folder_colors;
  for (std::size_t j = 0; j < folder.size(); ++j)
    folder_colors.push_back(cv::imread(folder[j].rgb_path, cv::IMREAD_UNCHANGED));
  const AccelerometerLog folder_log =
      AccelerometerLog::load(test::tumDir(kXyz) + "/accelerometer.txt");
  ASSERT_TRUE(fs::exists(dir + "/rec/accelerometer.txt")) << log;
  const AccelerometerLog recorded_log = AccelerometerLog::load(dir + "/rec/accelerometer.txt");
  EXPECT_EQ(recorded_log.size(), recorded.size());
  std::size_t previous = 0;
  for (std::size_t i = 0; i < recorded.size(); ++i) {
    const cv::Mat color = cv::imread(recorded[i].rgb_path, cv::IMREAD_UNCHANGED);
    std::size_t j = 0;
    while (j < folder.size() && cv::norm(color, folder_colors[j], cv::NORM_INF) != 0) ++j;
    ASSERT_LT(j, folder.size()) << "recorded colour " << i << " is no colour image of the folder";
    if (i > 0) {
      EXPECT_GT(j, previous) << i;
    }
    previous = j;
    // Up: the driver's sample is read after the pair's depth frame, so it may be the next
    // frame's (fr1/xyz turns slowly: well under a degree a frame).
    const auto recorded_up = recorded_log.upAt(recorded[i].rgb_time, 1e-4);
    const auto folder_up = folder_log.upAt(folder[j].rgb_time);
    ASSERT_TRUE(recorded_up && folder_up) << "recorded frame " << i;
    EXPECT_LT(std::acos(std::min(1.0, recorded_up->dot(*folder_up))) * 180 / M_PI, 1.0)
        << "frame " << j;
    // Depth: the recorded pair's, within the disparity step at that depth (plus the 0.1 mm of
    // the stream and TUM's 0.2 mm units); shifted pixels hidden behind nearer ones are lost.
    const cv::Mat depth = cv::imread(recorded[i].depth_path, cv::IMREAD_UNCHANGED);
    const cv::Mat truth = cv::imread(folder[j].depth_path, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(depth.type(), CV_16UC1);
    std::size_t valid = 0, kept = 0, within = 0;
    for (int y = 0; y < truth.rows; ++y)
      for (int x = 0; x < truth.cols; ++x) {
        const double z = truth.at<std::uint16_t>(y, x) / 5000.0;
        if (z <= 0) continue;
        ++valid;
        const double got = depth.at<std::uint16_t>(y, x) / 5000.0;
        if (got <= 0) continue;
        ++kept;
        const double step = -KinectV1Model::kA * z * z;
        within += std::abs(got - z) <= 0.55 * step + 0.0003;
      }
    ASSERT_GT(valid, 100000u);
    EXPECT_GE(static_cast<double>(kept), 0.95 * valid) << "frame " << j;
    EXPECT_GE(static_cast<double>(within), 0.999 * kept) << "frame " << j;
    if (i == 0)
      std::printf("frame %zu: %.2f %% of the folder's depth delivered, %.3f %% within the step\n",
                  j, 100.0 * kept / valid, 100.0 * within / kept);
  }
}

// rgbdmap maps the dump played as a Kinect, reports the unplug at its end, keeps the map and
// saves it on Ctrl-C.
TEST_F(OpenNI2Freenect, MapsTheFolderPlayedAsAKinect) {
#ifdef __SANITIZE_THREAD__
  GTEST_SKIP() << "under ThreadSanitizer fakenect delivers no frame to the driver within the read "
                  "timeout; release and ASan builds run this test";
#endif
  const std::string dir = test::freshDir();
  const std::string dump = writeDump(dir);
  test::Process map(withFakenect(dump, {"--source", "openni2", "--out", dir + "/map.pcd", "--stats",
                                        dir + "/stats.json", "--no-render", "-q"}),
                    dir + "/map.log");
  ASSERT_TRUE(waitForLog(dir + "/map.log", "camera stopped delivering frames", 120))
      << test::readFile(dir + "/map.log");
  map.signal(SIGINT);
  ASSERT_EQ(map.wait(120), 0) << test::readFile(dir + "/map.log");
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_GE(test::jsonNumber(stats, "frames_captured"), 8) << stats;
  EXPECT_GE(test::jsonNumber(stats, "disconnects"), 1) << stats;
  EXPECT_GT(test::loadMap(dir + "/map.pcd").size(), 10000u);
}

}  // namespace
}  // namespace rgbdmap
