// The camera paths of `rgbdmap synth` and its sensor errors: a walk that comes back every lap and
// keeps clear of every surface, a line that never comes back, and errors that change the images
// exactly as declared.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/sim/camera_path.hpp"
#include "rgbdmap/sim/synthetic_scene.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

const Eigen::Vector3d kRoomSize(8.0, 6.0, 3.0);

TEST(WalkPath, ComesBackEveryLapAndKeepsClearOfEverySurface) {
  const SyntheticScene scene = SyntheticScene::defaultRoom(kRoomSize);
  SyntheticSequenceOptions options;
  options.path = "walk";
  options.loop_seconds = 15.0;
  const auto path = makeCameraPath(scene.room(), options, 30.0);
  double walked = 0.0, nearest_return = 1e9;
  Eigen::Vector3d previous = path->pose(0.0).translation();
  for (double t = 0.0; t <= 30.0; t += 0.01) {
    const Eigen::Isometry3d pose = path->pose(t);
    ASSERT_TRUE(scene.isFreeSpace(pose.translation(), options.camera_margin)) << "t = " << t;
    // A camera that stays upright: its x axis stays level within the roll's few degrees.
    EXPECT_LT(std::abs(pose.linear().col(0).z()), 0.1) << "t = " << t;
    walked += (pose.translation() - previous).norm();
    previous = pose.translation();
    if (t > 14.0 && t < 16.0)
      nearest_return =
          std::min(nearest_return, (pose.translation() - path->pose(0.0).translation()).norm());
  }
  // Twice round a 5.6 x 3.6 m rectangle with 0.6 m corners (17.4 m a lap), plus the sway.
  EXPECT_GT(walked, 2 * 17.3);
  EXPECT_LT(walked, 2 * 17.3 * 1.15);
  // After a lap the camera is back where it began, up to the hand's sway (a few cm), looking
  // the same way within the sway's angles.
  EXPECT_LT(nearest_return, 0.1);
  const Eigen::Isometry3d lap = path->pose(0.0).inverse() * path->pose(15.0);
  EXPECT_LT(Eigen::AngleAxisd(lap.linear()).angle(), 0.5);
}

TEST(LinePath, NeverComesBack) {
  const SyntheticScene scene = SyntheticScene::defaultRoom(kRoomSize);
  SyntheticSequenceOptions options;
  options.path = "line";
  const double duration = 10.0;
  const auto path = makeCameraPath(scene.room(), options, duration);
  for (double a = 0.0; a <= duration; a += 0.1) {
    ASSERT_TRUE(scene.isFreeSpace(path->pose(a).translation(), options.camera_margin));
    for (double b = a + 2.0; b <= duration; b += 0.1)
      EXPECT_GT((path->pose(a).translation() - path->pose(b).translation()).norm(), 0.8)
          << a << " " << b;
  }
}

TEST(HandheldPath, IsStillTheDefaultOrbit) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  const SyntheticSequenceOptions options;
  EXPECT_EQ(options.path, "orbit");
  const auto path = makeCameraPath(scene.room(), options, 10.0);
  const HandheldPath orbit(scene.room(), options.seed, options.loop_seconds);
  for (double t : {0.0, 1.7, 9.3}) EXPECT_TRUE(path->pose(t).isApprox(orbit.pose(t), 1e-15)) << t;
}

// One or two frames with exact depth, written with `options`; returns the folder.
std::string writeFrames(const std::string& folder, SyntheticSequenceOptions options) {
  options.noise = false;
  options.fps = 1.0;
  options.camera.cx = 320.0;
  options.camera.cy = 240.0;
  writeSyntheticSequence(folder, SyntheticScene::defaultRoom(), options);
  return folder;
}

// The image of the first (or the last) line of a TUM list.
cv::Mat readListed(const std::string& folder, const std::string& list, bool last = false) {
  const std::string text = test::readFile(folder + "/" + list);
  std::istringstream lines(text);
  std::string name;
  for (std::string line; std::getline(lines, line);) {
    if (line.empty() || line[0] == '#') continue;
    name = line.substr(line.find(' ') + 1);
    if (!last) break;
  }
  return cv::imread(folder + "/" + name, cv::IMREAD_UNCHANGED);
}

TEST(SensorErrors, DepthScaleAndFocalLengthChangeTheImagesAsDeclared) {
  const std::string dir = test::freshDir();
  SyntheticSequenceOptions options;
  options.frames = 1;
  const cv::Mat exact = readListed(writeFrames(dir + "/exact", options), "depth.txt");
  options.depth_scale_error = 0.05;
  const cv::Mat far = readListed(writeFrames(dir + "/far", options), "depth.txt");
  options.depth_scale_error = 0.0;
  options.focal_error = 0.1;
  const cv::Mat zoomed = readListed(writeFrames(dir + "/zoomed", options), "depth.txt");
  ASSERT_FALSE(exact.empty());
  ASSERT_EQ(exact.type(), CV_16UC1);

  int compared = 0, moved = 0;
  for (int k = -20; k <= 20; ++k) {
    const int u = 320 + 10 * k, v = 240 + 10 * k;
    const double z = exact.at<std::uint16_t>(v, u);
    if (z == 0) continue;
    ++compared;
    // 5% too far (to the depth image's quantisation).
    EXPECT_NEAR(far.at<std::uint16_t>(v, u), 1.05 * z, 1.0) << u << " " << v;
    // A 10% longer lens sees the same ray 10% farther from the principal point.
    EXPECT_NEAR(zoomed.at<std::uint16_t>(240 + 11 * k, 320 + 11 * k), z, 0.002 * z)
        << u << " " << v;
    if (std::abs(zoomed.at<std::uint16_t>(v, u) - z) > 0.002 * z) ++moved;
  }
  EXPECT_GT(compared, 30);
  EXPECT_GT(moved, 10);  // the same pixel does see something else
}

TEST(SensorErrors, BrightnessDriftsWithTheDeclaredGain) {
  const std::string dir = test::freshDir();
  SyntheticSequenceOptions options;
  options.frames = 2;
  const cv::Mat exact = readListed(writeFrames(dir + "/exact", options), "rgb.txt");
  options.brightness_drift = 0.2;
  const cv::Mat first = readListed(writeFrames(dir + "/drift", options), "rgb.txt");
  // The first frame is at t = 0, where the gain is 1; so it must be the same image.
  ASSERT_FALSE(exact.empty());
  EXPECT_EQ(cv::norm(exact, first, cv::NORM_INF), 0.0);
  // The second frame, at t = 1 s, is 1 + 0.2 sin(2 pi / 6) = 1.173 times brighter.
  const cv::Mat second = readListed(dir + "/drift", "rgb.txt", true);
  const cv::Mat reference = readListed(dir + "/exact", "rgb.txt", true);
  ASSERT_FALSE(second.empty());
  ASSERT_FALSE(reference.empty());
  const double ratio = cv::mean(second)[1] / cv::mean(reference)[1];
  EXPECT_NEAR(ratio, 1.0 + 0.2 * std::sin(2.0 * M_PI / 6.0), 0.02);
}

TEST(SensorErrors, OutOfRangeOptionsAreRefused) {
  const std::string dir = test::freshDir();
  SyntheticSequenceOptions options;
  options.frames = 1;
  options.path = "spiral";
  EXPECT_THROW(writeSyntheticSequence(dir + "/a", SyntheticScene::defaultRoom(), options),
               InputError);
  options.path = "walk";
  options.focal_error = 0.5;
  EXPECT_THROW(writeSyntheticSequence(dir + "/b", SyntheticScene::defaultRoom(), options),
               InputError);
  // A walk inset so far that it leaves the room's free space is refused, naming the path.
  options.focal_error = 0.0;
  options.path_inset = 2.4;
  try {
    writeSyntheticSequence(dir + "/c", SyntheticScene::defaultRoom(), options);
    ADD_FAILURE() << "an inset beyond the room's middle was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("walk path"), std::string::npos) << e.what();
  }
  std::string output;
  EXPECT_NE(test::run(test::binary() + " synth --out " + dir + "/d --path spiral", &output), 0);
  EXPECT_NE(output.find("--path"), std::string::npos) << output;
}

}  // namespace
}  // namespace rgbdmap
