// OpenNI2 through the rgbdmap program: mapping the Kinect v1 recording,
// `record` and replaying what it wrote, `devices` and the no-camera message,
// and (when the OpenNI2 TUM driver plugin is built) a TUM folder as an OpenNI2
// device that unplugs and comes back.

#include <gtest/gtest.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <signal.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/drivers/openni2_source.hpp"
#include "rgbdmap/drivers/usb_cameras.hpp"
#include "rgbdmap/runtime/source_factory.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

std::string oniFile() { return test::dataDir() + "/oni/kinect_v1_12frames.oni"; }
using test::kRpy;
using test::kXyz;

// A counter from `--stats` JSON ("name": value).
double statValue(const std::string& json, const std::string& name) {
  const auto at = json.find("\"" + name + "\":");
  if (at == std::string::npos) {
    ADD_FAILURE() << "no " << name << " in " << json;
    return -1;
  }
  return std::stod(json.substr(at + name.size() + 3));
}

using test::waitUntil;

// Lines of a TUM list that name a frame (not comments).
std::size_t listedFrames(const std::string& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) n += !line.empty() && line[0] != '#';
  return n;
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Every listed image of a recorded folder exists, decodes, and the two lists
// pair one to one.
void expectCompleteRecording(const std::string& dir, std::size_t expected_frames) {
  const TumSequence sequence(dir);
  EXPECT_EQ(sequence.size(), expected_frames);
  EXPECT_EQ(sequence.unmatchedColor(), 0u);
  EXPECT_EQ(sequence.unmatchedDepth(), 0u);
  EXPECT_FALSE(sequence.hasGroundtruth());
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const cv::Mat depth = cv::imread(sequence[i].depth_path, cv::IMREAD_UNCHANGED);
    const cv::Mat color = cv::imread(sequence[i].rgb_path, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(depth.type(), CV_16UC1) << sequence[i].depth_path;
    ASSERT_EQ(color.type(), CV_8UC3) << sequence[i].rgb_path;
  }
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".partial"), std::string::npos) << entry.path();
}

bool cameraAttached() { return scanUsbCameras().anyCamera(); }

// Waits (up to `timeout_s`) until the log at `path` contains `text` `count` times.
bool waitForLog(const std::string& path, const std::string& text, double timeout_s,
                std::size_t count = 1) {
  return waitUntil([&] { return occurrences(test::readFile(path), text) >= count; }, timeout_s);
}

// `env -i` with only the sanitizers' settings kept: what a user's shell with no OpenNI2 or
// library-path setup gives a program.
std::vector<std::string> cleanEnvironment() {
  std::vector<std::string> command = {"/usr/bin/env", "-i"};
  for (const char* name : {"ASAN_OPTIONS", "LSAN_OPTIONS", "TSAN_OPTIONS", "UBSAN_OPTIONS"})
    if (const char* value = std::getenv(name)) command.push_back(std::string(name) + "=" + value);
  return command;
}

TEST(OpenNI2Cli, MapsTheKinectRecordingEndToEnd) {
  const std::string dir = test::freshDir();
  std::string output;
  const int code = test::run(test::binary() + " --source openni2:" + oniFile() + " --out " + dir +
                                 "/map.pcd --rate max --set keyframe.policy=interval "
                                 "--set keyframe.every_n=1 --stats " +
                                 dir + "/stats.json -q",
                             &output);
  ASSERT_EQ(code, 0) << output;
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_EQ(statValue(stats, "frames_captured"), 12);
  EXPECT_EQ(statValue(stats, "frames_processed"), 12);
  EXPECT_EQ(statValue(stats, "frames_dropped"), 0);
  EXPECT_EQ(statValue(stats, "frames_skipped"), 0);
  EXPECT_EQ(statValue(stats, "keyframes"), 12);
  EXPECT_EQ(statValue(stats, "frames_without_pose"),
            0);  // odometry, picked automatically
  const MapCloud map = test::loadMap(dir + "/map.pcd");
  EXPECT_GT(map.size(), 50000u);
  EXPECT_EQ(static_cast<double>(map.size()), statValue(stats, "map_points"));
  std::printf("map of the recording: %zu points\n", map.size());
  EXPECT_NE(output.find("poses: dense RGB-D tracking"), std::string::npos) << output;
}

TEST(OpenNI2Cli, NoCameraGivesAClearErrorNotACrash) {
  if (cameraAttached()) GTEST_SKIP() << "a camera is attached";
  std::string output;
  const int code = test::run(
      test::binary() + " --source openni2 --out " + test::freshDir() + "/map.pcd -q", &output);
  EXPECT_EQ(code, 2) << output;  // InputError; a crash would be 128 + signal
  EXPECT_NE(output.find("no camera found"), std::string::npos) << output;
  EXPECT_NE(output.find("USB bus"), std::string::npos) << output;
  EXPECT_NE(output.find("045e:02ae"), std::string::npos) << output;
}

TEST(OpenNI2Cli, DevicesSaysNoCameraWasFound) {
  if (cameraAttached()) GTEST_SKIP() << "a camera is attached";
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " devices", &output), 0) << output;
  EXPECT_NE(output.find("no camera found"), std::string::npos) << output;
  EXPECT_NE(output.find("OpenNI2"), std::string::npos) << output;
  EXPECT_NE(output.find("udevadm control --reload-rules"), std::string::npos) << output;
  EXPECT_TRUE(fs::exists(udevRulePath())) << udevRulePath();
}

TEST(OpenNI2Cli, RecordFromTheOniReplaysTheSameFrames) {
  const std::string dir = test::freshDir() + "/kinect";
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " record --source openni2:" + oniFile() + " --out " + dir,
                      &output),
            0)
      << output;
  EXPECT_NE(output.find("recorded 12 frames"), std::string::npos) << output;
  expectCompleteRecording(dir, 12);

  Config config;
  config.loadPreset("kinect_v1");
  config.replay.rate = 0;
  auto original = openSource("openni2:" + oniFile(), config);
  Config tum_units = config;  // the recorded folder holds TUM depth units, 5000 per metre
  tum_units.set("camera.depth_scale", "5000", "test");
  auto replay = openSource("tum:" + dir, tum_units);
  Frame a, b;
  std::size_t compared = 0;
  for (;;) {
    const ReadStatus sa = original->read(a);
    const ReadStatus sb = replay->read(b);
    ASSERT_EQ(sa, sb);
    if (sa == ReadStatus::kEnd) break;
    ASSERT_EQ(sa, ReadStatus::kFrame);
    EXPECT_NEAR(a.timestamp, b.timestamp, 5e-7);
    // Depth: the same measurements in units (1 mm = 5 TUM units), bit for bit,
    // except readings beyond 13.1 m (this Kinect reports some), which 16-bit
    // TUM units cannot hold: missing.
    cv::Mat mm_a, units_b;
    a.depth.convertTo(mm_a, CV_32S, 1000.0);
    b.depth.convertTo(units_b, CV_32S, 5000.0);
    cv::Mat expected = mm_a * 5;
    expected.setTo(0, expected > 65535);
    EXPECT_EQ(cv::norm(expected, units_b, cv::NORM_INF), 0) << compared;
    EXPECT_EQ(cv::norm(a.color, b.color, cv::NORM_INF), 0) << compared;
    ++compared;
  }
  EXPECT_EQ(compared, 12u);
}

TEST(OpenNI2Cli, RecordFromATumFolderWritesTheSameImages) {
  const std::string dir = test::freshDir() + "/copy";
  std::string output;
  ASSERT_EQ(
      test::run(test::binary() + " record --source tum:" + test::tumDir(kXyz) + " --out " + dir,
                &output),
      0)
      << output;
  const TumSequence original(test::tumDir(kXyz));
  expectCompleteRecording(dir, original.size());
  const TumSequence copy(dir);
  ASSERT_EQ(copy.size(), original.size());
  for (std::size_t i = 0; i < copy.size(); ++i) {
    EXPECT_NEAR(copy[i].rgb_time, original[i].rgb_time, 5e-7);
    const cv::Mat depth_a = cv::imread(original[i].depth_path, cv::IMREAD_UNCHANGED);
    const cv::Mat depth_b = cv::imread(copy[i].depth_path, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(depth_b.type(), CV_16UC1);
    EXPECT_EQ(cv::norm(depth_a, depth_b, cv::NORM_INF), 0) << copy[i].depth_path;
    const cv::Mat color_a = cv::imread(original[i].rgb_path, cv::IMREAD_COLOR);
    const cv::Mat color_b = cv::imread(copy[i].rgb_path, cv::IMREAD_COLOR);
    EXPECT_EQ(cv::norm(color_a, color_b, cv::NORM_INF), 0) << copy[i].rgb_path;
  }
  // --frames stops early; an existing recording is never overwritten.
  const std::string five = test::freshDir() + "/five";
  ASSERT_EQ(test::run(test::binary() + " record --source tum:" + test::tumDir(kXyz) + " --out " +
                          five + " --frames 5",
                      &output),
            0)
      << output;
  expectCompleteRecording(five, 5);
  EXPECT_EQ(
      test::run(test::binary() + " record --source tum:" + test::tumDir(kXyz) + " --out " + five,
                &output),
      2);
  EXPECT_NE(output.find("already holds a recording"), std::string::npos) << output;
  expectCompleteRecording(five, 5);
}

TEST(OpenNI2Cli, RecordStopsCleanlyOnSigintWithCompleteLists) {
  const std::string base = test::freshDir();
  const std::string dir = base + "/interrupted";
  // At the recorded speed the 100 frames take about 3.3 s; interrupt once a few are recorded.
  test::Process record({test::binary(), "record", "--source", "tum:" + test::tumDir(kRpy), "--out",
                        dir, "--set", "replay.rate=1"},
                       base + "/record.log");
  ASSERT_TRUE(waitUntil([&] { return listedFrames(dir + "/rgb.txt") > 5 || !record.running(); }))
      << test::readFile(base + "/record.log");
  record.signal(SIGINT);
  const int code = record.wait(30);
  const std::string log = test::readFile(base + "/record.log");
  ASSERT_EQ(code, 0) << log;
  const TumSequence sequence(dir);
  EXPECT_GT(sequence.size(), 5u) << log;
  EXPECT_LT(sequence.size(), 95u) << log;
  expectCompleteRecording(dir, sequence.size());
}

// The OpenNI2 TUM driver plugin (drivers/openni2_tum) builds a private OpenNI2
// runtime beside the binary; through it, a TUM folder is an OpenNI2 device that
// can be unplugged on request.
std::string privateOpenNI2Runtime() {
  const fs::path dir = fs::path(test::binary()).parent_path() / "openni2";
  if (!fs::exists(dir / "libOpenNI2.so.0") ||
      !fs::exists(dir / "OpenNI2/Drivers/libTumDevice.so.0"))
    return "";
  return dir.string();
}

TEST(OpenNI2Cli, RecordsATumDeviceAcrossAnUnplugBitIdentically) {
  const std::string runtime = privateOpenNI2Runtime();
  if (runtime.empty()) GTEST_SKIP() << "the OpenNI2 TUM driver plugin is not built";
  const std::string dir = test::freshDir() + "/through_openni2";
  const std::string uri =
      "tum:" + test::tumDir(kXyz) + "?disconnect_after=10&reconnect_after_ms=400";
  // A live device never ends by itself and loses frames a slow reader misses, so `--frames 20`
  // may never be reached (sanitizer builds): Ctrl-C ends the recording after a while.
  setenv("LD_LIBRARY_PATH", runtime.c_str(), 1);
  test::Process recorder(
      {test::binary(), "record", "--source", "openni2:" + uri, "--out", dir, "--frames", "20"},
      dir + ".log");
  unsetenv("LD_LIBRARY_PATH");
  for (int waited = 0; waited < 300 && recorder.running(); ++waited)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  if (recorder.running()) recorder.signal(SIGINT);
  ASSERT_EQ(recorder.wait(120), 0) << test::readFile(dir + ".log");
  const std::string output = test::readFile(dir + ".log");
  EXPECT_NE(output.find("reopened"), std::string::npos) << output;  // it did unplug and return
  // Each recorded frame is the folder's pair with the same stamp, bit for bit
  // (depth through DEPTH_100_UM and back to TUM units). A live device may
  // overwrite a frame the recorder was too slow for, so pairs are matched by
  // stamp rather than by position.
  const TumSequence original(test::tumDir(kXyz));
  const TumSequence copy(dir);
  expectCompleteRecording(dir, copy.size());
  // A loaded machine may lose some frames of a live device, but frames from after the unplug
  // (the folder's 11th pair on) must be there.
  ASSERT_GT(copy.size(), 0u) << output;
  EXPECT_GT(copy[copy.size() - 1].rgb_time, original[9].rgb_time + 1e-3)
      << "nothing recorded after the unplug: " << output;
  EXPECT_LE(copy.size(), 20u);
  std::size_t j = 0;
  for (std::size_t i = 0; i < copy.size(); ++i) {
    while (j < original.size() && original[j].rgb_time < copy[i].rgb_time - 5e-7) ++j;
    ASSERT_LT(j, original.size()) << "no original frame at " << copy[i].rgb_time;
    EXPECT_NEAR(copy[i].rgb_time, original[j].rgb_time, 5e-7) << i;
    // Depth is bit-identical to this pair's depth, or (when a stalled reader saw the depth
    // stream run one frame ahead of the colour stream) to a neighbouring pair's.
    const cv::Mat depth_b = cv::imread(copy[i].depth_path, cv::IMREAD_UNCHANGED);
    bool depth_found = false;
    for (std::size_t k = j > 0 ? j - 1 : 0; k <= std::min(j + 1, original.size() - 1); ++k)
      depth_found |= cv::norm(cv::imread(original[k].depth_path, cv::IMREAD_UNCHANGED), depth_b,
                              cv::NORM_INF) == 0;
    EXPECT_TRUE(depth_found) << "recorded depth " << i << " is no depth image of the folder";
    const cv::Mat color_a = cv::imread(original[j].rgb_path, cv::IMREAD_COLOR);
    const cv::Mat color_b = cv::imread(copy[i].rgb_path, cv::IMREAD_COLOR);
    EXPECT_EQ(cv::norm(color_a, color_b, cv::NORM_INF), 0) << i;
  }
}

TEST(OpenNI2Cli, MapsATumDeviceThatUnplugsAndComesBack) {
  const std::string runtime = privateOpenNI2Runtime();
  if (runtime.empty()) GTEST_SKIP() << "the OpenNI2 TUM driver plugin is not built";
  const std::string dir = test::freshDir();
  const std::string uri =
      "tum:" + test::tumDir(kXyz) + "?disconnect_after=12&reconnect_after_ms=400";
  // A live device never ends by itself: stop it with SIGINT once the folder has
  // played.
  setenv("LD_LIBRARY_PATH", runtime.c_str(), 1);
  test::Process map(
      {test::binary(), "--source", "openni2:" + uri, "--out", dir + "/map.pcd", "--stats",
       dir + "/stats.json", "--set", "keyframe.policy=interval", "--no-render", "-q"},
      dir + "/map.log");
  unsetenv("LD_LIBRARY_PATH");
  // Unplugged after 12 and 24 frames; the third stop is the end of the folder (a live camera
  // then waits for more).
  EXPECT_TRUE(waitForLog(dir + "/map.log", "camera stopped delivering frames", 120, 3))
      << test::readFile(dir + "/map.log");
  map.signal(SIGINT);
  const int code = map.wait(60);
  const std::string log = test::readFile(dir + "/map.log");
  ASSERT_EQ(code, 0) << log;
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_GE(statValue(stats, "disconnects"), 1) << log;
  // A live device keeps its own pace: frames a busy reader misses, or that play while the
  // streams restart, are lost, so how many are captured depends on the machine. What must hold:
  // a frame the device played after the unplug (the 13th onwards) was mapped.
  const TumSequence sequence(test::tumDir(kXyz));
  EXPECT_LE(statValue(stats, "frames_captured"), sequence.size()) << log;
  double last_keyframe = 0;
  {
    std::ifstream keyframes(dir + "/map_keyframes.txt");
    for (std::string line; std::getline(keyframes, line);)
      if (!line.empty() && line[0] != '#') last_keyframe = std::stod(line);
  }
  EXPECT_GT(last_keyframe, sequence[11].rgb_time + 1e-4)
      << "nothing mapped after the unplug: " << log;
  // Nothing mapped before the unplug is lost: the checkpoint written when the camera went away
  // (and every later one) holds no more points than the final map, but for the few noisy surface
  // points later views carve away (the map is a TSDF: more views can remove a point).
  const std::size_t final_points = test::loadMap(dir + "/map.pcd").size();
  EXPECT_GT(final_points, 10000u);
  std::size_t checkpoints = 0;
  for (std::size_t at = log.find("checkpoint: "); at != std::string::npos;
       at = log.find("checkpoint: ", at + 1)) {
    const std::size_t points = std::stoul(log.substr(at + 12));
    EXPECT_LE(static_cast<double>(points), 1.01 * static_cast<double>(final_points)) << log;
    ++checkpoints;
  }
  EXPECT_GE(checkpoints, 1u) << "no checkpoint written at the unplug: " << log;
  EXPECT_NE(log.find("camera is back"), std::string::npos) << log;
}

// A TUM folder through the OpenNI2 driver plugin maps exactly like the folder
// read directly. The device plays at its own pace, so the frames it mapped (its
// keyframe list, every frame a keyframe) are mapped again straight from a copy
// of the folder that lists only those frames; poses come from the same ground
// truth file in both runs.
// No setup and finite: from a clean environment (no LD_LIBRARY_PATH; rgbdmap finds its private
// OpenNI2 runtime through its RUNPATH), a TUM folder through the OpenNI2 driver plays like a
// recording: `--rate max` maps every frame and the run ends by itself at the end of the folder.
TEST(OpenNI2Cli, ATumFolderThroughTheDriverGivesTheSameMapAsReadDirectly) {
  const std::string runtime = privateOpenNI2Runtime();
  if (runtime.empty()) GTEST_SKIP() << "the OpenNI2 TUM driver plugin is not built";
  const std::string dir = test::freshDir();
  const std::string folder = test::tumDir(kXyz);
  const std::vector<std::string> common = {
      "--config",    "tum_fr1",
      "--set",       "pose.source=trajectory",
      "--set",       "pose.trajectory=" + folder + "/groundtruth.txt",
      "--set",       "keyframe.every_n=1",
      "--rate",      "max",
      "--no-render", "-q"};

  std::vector<std::string> live = cleanEnvironment();
  for (const std::string& arg :
       {test::binary(), std::string("--source"), "openni2:tum:" + folder, std::string("--stats"),
        dir + "/device.json", std::string("--out"), dir + "/device.pcd"})
    live.push_back(arg);
  live.insert(live.end(), common.begin(), common.end());
  test::Process device_run(live, dir + "/device.log");
  ASSERT_EQ(device_run.wait(300), 0) << test::readFile(dir + "/device.log");
  const std::string stats = test::readFile(dir + "/device.json");
  const TumSequence sequence(folder);
  EXPECT_EQ(statValue(stats, "frames_captured"), static_cast<double>(sequence.size())) << stats;
  EXPECT_EQ(statValue(stats, "frames_processed"), static_cast<double>(sequence.size())) << stats;
  EXPECT_EQ(statValue(stats, "disconnects"), 0) << stats;

  std::vector<std::string> direct = {test::binary(), "--source", "tum:" + folder, "--out",
                                     dir + "/direct.pcd"};
  direct.insert(direct.end(), common.begin(), common.end());
  test::Process direct_run(direct, dir + "/direct.log");
  ASSERT_EQ(direct_run.wait(300), 0) << test::readFile(dir + "/direct.log");

  // The same map: the same voxels with the same points, up to float rounding of
  // the stamps (microseconds from the device) and of depth (0.1 mm units
  // instead of TUM's 0.2 mm).
  const MapCloud a = test::loadMap(dir + "/device.pcd");
  const MapCloud b = test::loadMap(dir + "/direct.pcd");
  // 32 frames of fr1/xyz: about 34k surface voxels (the TSDF keeps one point per surface voxel).
  ASSERT_GT(a.size(), 20000u);
  EXPECT_NEAR(static_cast<double>(a.size()), static_cast<double>(b.size()), 1e-4 * b.size());
  // Each surface point of one map has its twin in the other: the surfaces sit where the TSDF
  // crosses zero, which the depth units (0.1 mm from the device, 0.2 mm in TUM's PNGs) move by a
  // fraction of a millimetre.
  pcl::KdTreeFLANN<pcl::PointXYZRGB> tree;
  tree.setInputCloud(a.makeShared());
  std::vector<int> index(1);
  std::vector<float> squared(1);
  std::size_t same = 0;
  for (const auto& q : b.points) {
    if (tree.nearestKSearch(q, 1, index, squared) != 1) continue;
    const pcl::PointXYZRGB& p = a.points[static_cast<std::size_t>(index[0])];
    same += squared[0] < 1e-3f * 1e-3f && std::abs(int(p.r) - int(q.r)) <= 2 &&
            std::abs(int(p.g) - int(q.g)) <= 2 && std::abs(int(p.b) - int(q.b)) <= 2;
  }
  EXPECT_GE(same, static_cast<std::size_t>(0.995 * static_cast<double>(b.size())))
      << same << " of " << b.size() << " points agree";
}

// A camera that stays away for 10 s is waited for with backed-off reopen attempts (not one
// every 200 ms) and costs one checkpoint, not one per attempt.
TEST(OpenNI2Cli, ACameraAwayForTenSecondsCostsAFewReopenAttemptsAndOneCheckpoint) {
  if (privateOpenNI2Runtime().empty()) GTEST_SKIP() << "the OpenNI2 TUM driver plugin is not built";
  const std::string dir = test::freshDir();
  const std::string uri =
      "tum:" + test::tumDir(kXyz) + "?disconnect_after=10&reconnect_after_ms=10000";
  std::vector<std::string> command = cleanEnvironment();
  for (const std::string& arg :
       {test::binary(), std::string("--source"), "openni2:" + uri, std::string("--out"),
        dir + "/map.pcd", std::string("--set"), std::string("checkpoint.every_seconds=0"),
        std::string("--set"), std::string("checkpoint.every_keyframes=0"),
        std::string("--no-render"), std::string("-q")})
    command.push_back(arg);
  test::Process map(command, dir + "/map.log");
  ASSERT_TRUE(waitForLog(dir + "/map.log", "camera stopped delivering frames", 120))
      << test::readFile(dir + "/map.log");
  ASSERT_TRUE(waitForLog(dir + "/map.log", "camera is back", 120))
      << test::readFile(dir + "/map.log");
  map.signal(SIGINT);
  ASSERT_EQ(map.wait(120), 0) << test::readFile(dir + "/map.log");
  const std::string log = test::readFile(dir + "/map.log");
  const std::size_t away = log.find("camera stopped delivering frames");
  const std::size_t back = log.find("camera is back");
  ASSERT_LT(away, back) << log;
  const std::string outage = log.substr(away, back - away);
  // At once, then after 0.5, 1, 2, 4 and 5 s: the sixth attempt (12.5 s) finds it back; a
  // slow machine may fit one more attempt in before the driver's 10 s are up.
  const std::size_t attempts = occurrences(outage, "reopen attempt");
  EXPECT_GE(attempts, 3u) << outage;
  EXPECT_LE(attempts, 7u) << outage;
  EXPECT_EQ(occurrences(outage, "map checkpointed"), 1u) << outage;
  // The checkpoint line is logged by the writer thread: count those up to the reopen.
  EXPECT_EQ(occurrences(log.substr(0, back), "checkpoint: "), 1u) << log;
}

}  // namespace
}  // namespace rgbdmap

namespace rgbdmap {
namespace {

TEST(OpenNI2Cli, PresetFollowsTheCamera) {
  // A TUM folder through the OpenNI2 driver is the folder's camera; a recording a Kinect's.
  EXPECT_EQ(presetForSource("openni2:tum:" + test::tumDir(kXyz)), "tum_fr1");
  EXPECT_EQ(presetForSource("openni2:tum:" + test::tumDir(kXyz) + "?loop=1"), "tum_fr1");
  EXPECT_EQ(presetForSource("openni2:" + oniFile()), "kinect_v1");
  // No camera attached: the Kinect preset (the message about the missing camera comes later).
  if (!cameraAttached()) {
    EXPECT_EQ(presetForSource("openni2"), "kinect_v1");
  }
}

}  // namespace
}  // namespace rgbdmap
