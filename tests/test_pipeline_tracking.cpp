// The live path end to end: every frame is tracked (and written to MAP_trajectory.txt, lost ones
// at their predicted pose), keyframes are fused on the fusion thread, checkpoints carry the
// trajectory, and a map built from tracked poses is close to the map built from exact ones.
#include <gtest/gtest.h>
#include <pcl/common/transforms.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <thread>

#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::kRpy;
using test::kXyz;

struct MapRun {
  int exit_code = -1;
  std::string output;
  std::string stats;
};

MapRun mapFolder(const std::string& folder, const std::string& dir, const std::string& extra) {
  MapRun r;
  r.exit_code =
      test::run(test::binary() + " --source tum:" + folder + " --out " + dir +
                    "/map.pcd --rate max -q --no-render --stats " + dir + "/stats.json " + extra,
                &r.output);
  r.stats = test::readFile(dir + "/stats.json");
  return r;
}

// Non-comment lines of a text file.
std::size_t dataLines(const std::string& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') ++n;
  return n;
}

bool waitFor(const std::function<bool()>& condition, std::chrono::seconds timeout) {
  return test::waitUntil(condition, std::chrono::duration<double>(timeout).count());
}

TEST(PipelineTracking, EveryFrameIsTrackedCountedAndWrittenToTheTrajectory) {
  const std::string dir = test::freshDir();
  const std::string folder = test::tumDir(kXyz);
  const MapRun r = mapFolder(folder, dir, "--set pose.source=odometry");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // One line per frame, at the frame's colour stamp, in order.
  const TumSequence sequence(folder);
  const Trajectory frames = Trajectory::load(dir + "/map_trajectory.txt");
  ASSERT_EQ(frames.size(), sequence.size());
  for (std::size_t i = 0; i < frames.size(); ++i)
    EXPECT_NEAR(frames[i].timestamp, sequence[i].rgb_time, 1e-6) << i;
  // The keyframes are some of those frames, with the same poses.
  const Trajectory keyframes = Trajectory::load(dir + "/map_keyframes.txt");
  ASSERT_GE(keyframes.size(), 2u);
  EXPECT_LT(keyframes.size(), frames.size());  // motion keyframing by default with odometry
  for (const StampedPose& k : keyframes.poses()) {
    const auto pose = frames.interpolate(k.timestamp, 1e-6);
    ASSERT_TRUE(pose.has_value()) << k.timestamp;
    EXPECT_LT((pose->translation() - k.pose.translation()).norm(), 1e-5);
  }

  // Counters: every frame tracked, lost or relocalised; tracking latency per frame.
  const double tracked = test::jsonNumber(r.stats, "frames_tracked");
  const double lost = test::jsonNumber(r.stats, "frames_lost");
  const double relocalised = test::jsonNumber(r.stats, "frames_relocalised");
  EXPECT_EQ(tracked + lost + relocalised, 32.0) << r.stats;
  EXPECT_EQ(test::jsonNumber(r.stats, "keyframes"), static_cast<double>(keyframes.size()));
  EXPECT_EQ(test::jsonNumber(r.stats, "keyframes_deferred"), 0.0);  // lossless replay waits
  EXPECT_NE(r.stats.find("\"track\": {\"count\": 32,"), std::string::npos) << r.stats;
  EXPECT_NE(r.stats.find("\"pose\": {\"count\": 32,"), std::string::npos) << r.stats;
  // The frames really were tracked: fr1/xyz moves a few centimetres along x.
  const AbsoluteTrajectoryError ate =
      absoluteTrajectoryError(frames, Trajectory::load(folder + "/groundtruth.txt"));
  std::cout << "ATE over every frame: " << ate.translation.rmse << " m\n";
  EXPECT_LT(ate.translation.rmse, 0.02);
}

TEST(PipelineTracking, LostFramesKeepTheirPredictedPoseAndAreNotMapped) {
  // Three frames in the middle have no depth at all: tracking cannot use them.
  const std::string dir = test::freshDir();
  const std::string copy = test::copySequence(test::tumDir(kXyz), dir + "/blanked");
  cv::imwrite(copy + "/blank.png", cv::Mat::zeros(480, 640, CV_16UC1));
  {
    std::ifstream in(copy + "/depth.txt");
    std::string text, line;
    int entry = 0;
    while (std::getline(in, line)) {
      if (!line.empty() && line[0] != '#' && (++entry >= 15 && entry <= 17))
        line = line.substr(0, line.find(' ')) + " blank.png";
      text += line + "\n";
    }
    in.close();
    std::ofstream(copy + "/depth.txt") << text;
  }
  const MapRun r = mapFolder(copy, dir, "--set pose.source=odometry");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const double lost = test::jsonNumber(r.stats, "frames_lost");
  EXPECT_GE(lost, 3.0) << r.stats;
  EXPECT_EQ(test::jsonNumber(r.stats, "frames_without_pose"), lost);
  // Still one line per frame, lost ones included.
  const Trajectory frames = Trajectory::load(dir + "/map_trajectory.txt");
  EXPECT_EQ(frames.size(), 32u);
  // No keyframe comes from a frame without depth, and tracking came back afterwards.
  const TumSequence sequence(copy);
  std::set<double> blank_stamps;
  for (std::size_t i = 0; i < sequence.size(); ++i)
    if (sequence[i].depth_path.find("blank.png") != std::string::npos)
      blank_stamps.insert(sequence[i].rgb_time);
  ASSERT_EQ(blank_stamps.size(), 3u);
  const Trajectory keyframes = Trajectory::load(dir + "/map_keyframes.txt");
  for (const StampedPose& k : keyframes.poses())
    EXPECT_EQ(blank_stamps.count(k.timestamp), 0u) << k.timestamp;
  EXPECT_GE(
      test::jsonNumber(r.stats, "frames_tracked") + test::jsonNumber(r.stats, "frames_relocalised"),
      32.0 - lost);
}

// Every entry of a TUM list (rgb.txt, depth.txt) points at its first image: a camera that stands
// still (each frame keeps its own stamp).
void freezeList(const std::string& path) {
  std::ifstream in(path);
  std::string text, line, first;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') {
      const std::string file = line.substr(line.find(' ') + 1);
      if (first.empty()) first = file;
      line = line.substr(0, line.find(' ')) + " " + first;
    }
    text += line + "\n";
  }
  in.close();
  std::ofstream(path) << text;
}

TEST(PipelineTracking, ATrackedCameraStandingStillAddsNoKeyframeByDefault) {
  const std::string dir = test::freshDir();
  const std::string copy = test::copySequence(test::tumDir(kXyz), dir + "/still");
  freezeList(copy + "/rgb.txt");
  freezeList(copy + "/depth.txt");
  // Default keyframing with odometry (what a live camera gets): motion, one keyframe.
  fs::create_directories(dir + "/motion");
  const MapRun still = mapFolder(copy, dir + "/motion", "--set pose.source=odometry");
  ASSERT_EQ(still.exit_code, 0) << still.output;
  EXPECT_EQ(test::jsonNumber(still.stats, "frames_tracked"), 32.0) << still.stats;
  EXPECT_EQ(test::jsonNumber(still.stats, "keyframes"), 1.0) << still.stats;
  // The interval policy would fuse the same view again every 10 frames.
  fs::create_directories(dir + "/interval");
  const MapRun interval = mapFolder(copy, dir + "/interval",
                                    "--set pose.source=odometry --set keyframe.policy=interval");
  ASSERT_EQ(interval.exit_code, 0) << interval.output;
  EXPECT_EQ(test::jsonNumber(interval.stats, "keyframes"), 4.0) << interval.stats;
}

TEST(PipelineTracking, CheckpointsCarryThePerFrameTrajectory) {
  const std::string dir = test::freshDir();
  // Half speed (100 frames in ~6.6 s); a checkpoint every 3 keyframes (every 10th frame with
  // ground truth), so the first one holds at least 21 frames and comes well before the end.
  test::Process p({test::binary(), "--source", "tum:" + test::tumDir(kRpy), "--out",
                   dir + "/map.pcd", "--rate", "0.5", "--no-render", "-q", "--set",
                   "checkpoint.every_keyframes=3", "--set", "checkpoint.every_seconds=0", "--set",
                   "checkpoint.min_seconds=0", "--stats", dir + "/stats.json"},
                  dir + "/log.txt");
  ASSERT_TRUE(waitFor([&] { return fs::exists(dir + "/map_trajectory.txt"); }, 120s))
      << test::readFile(dir + "/log.txt");
  // Files are renamed into place whole: what is there is one checkpoint's trajectory.
  const std::size_t at_checkpoint = dataLines(dir + "/map_trajectory.txt");
  const bool still_running = p.running();
  EXPECT_GE(at_checkpoint, 21u);
  EXPECT_TRUE(fs::exists(dir + "/map_keyframes.txt"));
  if (still_running) {
    EXPECT_LT(at_checkpoint, 100u) << "written before the end of the run";
  }
  EXPECT_EQ(p.wait(), 0) << test::readFile(dir + "/log.txt");
  // The final files hold every frame and keyframe mapped. A machine too slow for the pace drops
  // frames or lets a keyframe go (a clean run of .ci/run here fused 9 of the 10 under TSan):
  // how many is the stats file's to say, as fast machines map all 100 frames and 10 keyframes.
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_EQ(static_cast<double>(dataLines(dir + "/map_trajectory.txt")),
            test::jsonNumber(stats, "frames_processed"))
      << stats;
  EXPECT_EQ(static_cast<double>(dataLines(dir + "/map_keyframes.txt")),
            test::jsonNumber(stats, "keyframes"))
      << stats;
  EXPECT_EQ(test::jsonNumber(stats, "frames_processed") + test::jsonNumber(stats, "frames_dropped"),
            100.0)
      << stats;
}

TEST(PipelineTracking, TwoOdometryReplaysGiveIdenticalMapsAndTrajectories) {
  // Fusion runs on its own thread; in a lossless replay the tracking thread waits for a fusion
  // slot, so the keyframes and their order do not depend on timing.
  const std::string dir = test::freshDir();
  for (const char* name : {"a", "b"}) {
    fs::create_directories(dir + "/" + name);
    const MapRun r = mapFolder(test::tumDir(kXyz), dir + "/" + name, "--set pose.source=odometry");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  EXPECT_EQ(test::readFile(dir + "/a/map.pcd"), test::readFile(dir + "/b/map.pcd"));
  EXPECT_EQ(test::readFile(dir + "/a/map_trajectory.txt"),
            test::readFile(dir + "/b/map_trajectory.txt"));
  EXPECT_EQ(test::readFile(dir + "/a/map_keyframes.txt"),
            test::readFile(dir + "/b/map_keyframes.txt"));
}

// F-score at 1 cm of a map against the synthetic scene; an odometry map (in the first camera's
// frame) is first placed with the true pose of the first frame, so only tracking errors count.
double fScore(const std::string& map_path, const std::string& scene,
              const Eigen::Isometry3d& first_camera) {
  pcl::PointCloud<pcl::PointXYZRGB> map = loadMapFile(map_path);
  pcl::transformPointCloud(map, map, first_camera.matrix().cast<float>());
  const SyntheticGroundTruth truth = loadSyntheticGroundTruth(scene);
  const MapScore score = evaluateMap(map, truth.scene, truth.visible_surface, 0.01);
  std::cout << map_path << ": " << score.toJson() << "\n";
  return score.f_score;
}

TEST(PipelineTracking, OdometryMapOfASyntheticRoomIsCloseToTheExactPoseMap) {
#ifdef __SANITIZE_THREAD__
  GTEST_SKIP()
      << "synth renders on OpenCV's TBB threads, whose synchronisation ThreadSanitizer cannot see; "
         "the other pipeline tests cover the threads, release and ASan run this one";
#endif
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " synth --out " + dir + "/room --frames 60", &output), 0)
      << output;
  const std::string room = dir + "/room";
  // The same keyframing for both, so only the poses differ.
  fs::create_directories(dir + "/exact");
  fs::create_directories(dir + "/odometry");
  const MapRun exact = mapFolder(room, dir + "/exact", "--set keyframe.policy=motion");
  ASSERT_EQ(exact.exit_code, 0) << exact.output;
  const MapRun tracked =
      mapFolder(room, dir + "/odometry", "--set keyframe.policy=motion --set pose.source=odometry");
  ASSERT_EQ(tracked.exit_code, 0) << tracked.output;
  EXPECT_EQ(test::jsonNumber(tracked.stats, "frames_lost"), 0.0);

  const Trajectory truth = Trajectory::load(room + "/groundtruth.txt");
  const Trajectory frames = Trajectory::load(dir + "/odometry/map_trajectory.txt");
  ASSERT_EQ(frames.size(), 60u);
  const auto first = truth.interpolate(frames[0].timestamp);
  ASSERT_TRUE(first.has_value());
  const double f_exact = fScore(dir + "/exact/map.pcd", room, Eigen::Isometry3d::Identity());
  const double f_tracked = fScore(dir + "/odometry/map.pcd", room, *first);
  std::cout << "F@1cm exact poses " << f_exact << ", odometry " << f_tracked << "\n";
  EXPECT_GT(f_exact, 0.95);
  EXPECT_GE(f_tracked, f_exact - 0.03);
}

}  // namespace
}  // namespace rgbdmap
