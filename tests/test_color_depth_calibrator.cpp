// rgbdmap calibrate: the colour camera's focal length and the depth camera's pose in it, found
// from where depth outlines meet colour edges, against the truth of rendered captures.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "rgbdmap/tracking/color_depth_calibrator.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

// The bounds: the extrinsic within 5 mm and 0.3 degrees, the focal length within 0.5%.
void expectNear(const ColorDepthCalibration& found, const Eigen::Isometry3d& truth, double fx) {
  const double offset_mm =
      (found.color_from_depth.translation() - truth.translation()).norm() * 1000.0;
  const double angle_deg =
      Eigen::AngleAxisd(found.color_from_depth.linear() * truth.linear().transpose()).angle() *
      180.0 / M_PI;
  std::cout << "extrinsic off by " << offset_mm << " mm, " << angle_deg << " deg; fx " << found.fx
            << ", fy " << found.fy << " (truth " << fx << ")\n";
  EXPECT_LT(offset_mm, 5.0);
  EXPECT_LT(angle_deg, 0.3);
  EXPECT_LT(std::abs(found.fx / fx - 1.0), 0.005);
  EXPECT_LT(std::abs(found.fy / fx - 1.0), 0.005);
}

Eigen::Isometry3d depthCamera(const Eigen::Vector3d& position, const Eigen::Vector3d& degrees) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d r = degrees * M_PI / 180.0;
  pose.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).matrix();
  pose.translation() = position;
  return pose;
}

// Captures of the default room along its walls, where outlines lie at every depth (seen from the
// room's centre, most are far, and a longer focal length looks like a depth camera nearer the
// scene): colour through `lens`, depth from a camera of its own (`depth`, at `color_from_depth`).
std::vector<CalibrationFrame> renderCaptures(const CameraIntrinsics& lens,
                                             const CameraIntrinsics& depth,
                                             const Eigen::Isometry3d& color_from_depth) {
#if defined(__SANITIZE_THREAD__)
  // The renderer's OpenCV loops run on TBB's uninstrumented workers (as in `rgbdmap synth`);
  // the calibrator's own threads (a WorkerPool) are what this build checks.
  cv::setNumThreads(1);
#endif
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  const SyntheticRenderer color_renderer(scene, lens), depth_renderer(scene, depth);
  SyntheticSequenceOptions options;
  options.path = "walk";
  const auto path = makeCameraPath(scene, options, options.loop_seconds);
  std::vector<CalibrationFrame> frames;
  cv::Mat color_image, incidence, hits, unused, gray8;
  for (int i = 0; i < 30; ++i) {
    const Eigen::Isometry3d pose = path->pose(options.loop_seconds * i / 30.0);
    CalibrationFrame frame;
    color_renderer.render(pose, unused, color_image, incidence, hits);
    cv::cvtColor(color_image, gray8, cv::COLOR_BGR2GRAY);
    gray8.convertTo(frame.gray, CV_32F);
    depth_renderer.render(pose * color_from_depth, frame.depth, unused, incidence, hits);
    frames.push_back(frame);
  }
  return frames;
}

// Sets the keys calibrate printed ("map with: --set k=v ..."), as a user would; false when none.
bool printedKeys(const std::string& output, Config& config) {
  const std::string marker = "map with:";
  const auto line = output.find(marker);
  if (line == std::string::npos) return false;
  std::istringstream keys(
      output.substr(line + marker.size(), output.find('\n', line) - line - marker.size()));
  std::string word, assignment;
  while (keys >> word >> assignment) {
    if (word != "--set") return false;
    config.setAll({assignment}, "calibrate's output");
  }
  return true;
}

// The calibration the keys hold, with the focal length that was estimated (`fx`, `fy`: the
// colour camera's or the depth camera's).
ColorDepthCalibration keysAsCalibration(const CameraOptions& c, double fx, double fy) {
  ColorDepthCalibration found;
  found.fx = fx;
  found.fy = fy;
  found.color_from_depth = c.colorFromDepth();
  return found;
}

TEST(ColorDepthCalibrator, FindsTheDepthCameraAndTheFocalLengthOfRenderedCaptures) {
  // A Kinect-like pair: depth 2.5 cm aside with a focal length of 580 px, turned by 0.9 deg;
  // the colour lens 1% longer than the 525 px declared.
  const Eigen::Isometry3d truth = depthCamera({0.025, 0.003, -0.002}, {0.3, -0.8, 0.2});
  CameraIntrinsics color;  // declared: 640 x 480, f 525
  CameraIntrinsics lens = color;
  lens.fx = lens.fy = 525.0 * 1.01;
  CameraIntrinsics depth = color;
  depth.fx = depth.fy = 580.0;
  std::vector<CalibrationFrame> frames = renderCaptures(lens, depth, truth);
  WorkerPool pool(2);
  const ColorDepthCalibrator calibrator(ColorDepthCalibrator::Config{}, color, depth);
  ColorDepthCalibration guess;  // registered, as declared
  const CalibrationReport report = calibrator.estimate(frames, guess, pool);
  std::cout << "outlines " << report.rms_before << " px from their edges (" << report.edges_before
            << ") at the guess, " << report.rms_after << " px (" << report.edges_after
            << ") calibrated\n";
  expectNear(report.calibration, truth, lens.fx);
  EXPECT_LT(report.rms_after, report.rms_before);

  // A guess 4 cm beside the truth puts outlines 10-20 px off their edges, beyond the search:
  // from it alone the estimate runs off (measured); the starts tried beside it find the truth.
  ColorDepthCalibration far_guess;
  far_guess.color_from_depth.translation() = Eigen::Vector3d(-0.015, 0.0, 0.0);
  expectNear(calibrator.estimate(frames, far_guess, pool).calibration, truth, lens.fx);

  // Without outlines (a flat wall filling the view) there is nothing to go by: said, not guessed.
  for (CalibrationFrame& frame : frames) frame.depth.setTo(2.0f);
  try {
    calibrator.estimate(frames, guess, pool);
    ADD_FAILURE() << "calibrated from captures without outlines";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("too few outlines"), std::string::npos) << e.what();
  }
}

// A depth camera whose intrinsics nobody gave (a user's raw Kinect streams, a dataset without
// them): its focal length is found, the colour camera's kept. Started from the colour camera's
// 525 px, the depth camera's 580 px put outlines 30 px off their edges at the image's sides.
TEST(ColorDepthCalibrator, FindsTheDepthCamerasFocalLengthWhenOnlyTheColourCamerasIsKnown) {
  const Eigen::Isometry3d truth = depthCamera({0.025, 0.003, -0.002}, {0.3, -0.8, 0.2});
  CameraIntrinsics color;  // declared and exact: 640 x 480, f 525
  CameraIntrinsics depth = color;
  depth.fx = depth.fy = 580.0;
  const std::vector<CalibrationFrame> frames = renderCaptures(color, depth, truth);
  WorkerPool pool(2);
  ColorDepthCalibrator::Config config;
  config.estimate_depth_focal = true;
  // Given the colour camera's intrinsics for the depth camera's, as calibrate does without keys.
  const ColorDepthCalibrator calibrator(config, color, color);
  const CalibrationReport report = calibrator.estimate(frames, ColorDepthCalibration{}, pool);
  const ColorDepthCalibration& found = report.calibration;
  EXPECT_EQ(found.fx, 525.0);
  EXPECT_EQ(found.fy, 525.0);
  std::cout << "depth focal length " << 525.0 * found.depth_focal_scale << " px (truth 580)\n";
  EXPECT_LT(std::abs(525.0 * found.depth_focal_scale / 580.0 - 1.0), 0.005);
  ColorDepthCalibration as_depth = found;  // the focal length bound on the depth camera's
  as_depth.fx = as_depth.fy = 525.0 * found.depth_focal_scale;
  expectNear(as_depth, truth, 580.0);
}

// Through the command line: a rendered unregistered orbit with sensor noise; the keys printed.
TEST(ColorDepthCalibrator, CalibrateFindsTheKeysOfAnUnregisteredSequence) {
  const std::string sequence = test::sharedSynthetic(
      "orbit_100_unregistered",
      " --frames 100 --fps 10 --seed 5 --depth-camera -0.02,0.005,0.003,-0.5,0.6,-0.3"
      " --depth-focal 575 --focal-error -0.012");
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " calibrate --source tum:" + sequence +
                          " --every 1 --set camera.depth_fx=575 --set camera.depth_fy=575 --out " +
                          dir + "/calibrated.yaml",
                      &output),
            0)
      << output;
  std::cout << output;
  EXPECT_EQ(output.find("warning"), std::string::npos) << output;
  // The keys as printed, set as a user would set them.
  Config config;
  ASSERT_TRUE(printedKeys(output, config)) << output;
  const CameraOptions& c = config.camera;
  expectNear(keysAsCalibration(c, c.fx, c.fy),
             depthCamera({-0.02, 0.005, 0.003}, {-0.5, 0.6, -0.3}), 525.0 * 0.988);
  EXPECT_EQ(c.depth_fx, 575.0);
  EXPECT_EQ(c.depth_fy, 575.0);
  // The config file holds the same camera.
  EXPECT_NE(test::readFile(dir + "/calibrated.yaml").find("depth_fx: 575"), std::string::npos);

  // Told the depth camera's offset along the view, it keeps it and finds the rest.
  ASSERT_EQ(test::run(test::binary() + " calibrate --source tum:" + sequence +
                          " --every 1 --fix-depth-z --set camera.depth_fx=575 --set "
                          "camera.depth_fy=575 --set camera.depth_z=0.003",
                      &output),
            0)
      << output;
  EXPECT_NE(output.find("--set camera.depth_z=0.003 "), std::string::npos) << output;
}

// Through the command line with the default configuration (no depth keys): the depth camera's
// focal length found, the colour camera's kept, the offset along the view kept at 0.
TEST(ColorDepthCalibrator, CalibrateWithoutDepthKeysFindsTheDepthCamerasFocalLength) {
  const std::string sequence = test::sharedSynthetic(
      "orbit_100_unregistered_585",
      " --frames 100 --fps 10 --seed 6 --depth-camera 0.025,-0.003,0,0.3,0.5,-0.2"
      " --depth-focal 585");
  std::string output;
  ASSERT_EQ(
      test::run(test::binary() + " calibrate --source tum:" + sequence + " --every 1", &output), 0)
      << output;
  std::cout << output;
  EXPECT_NE(output.find("depth camera: fx"), std::string::npos) << output;
  Config config;
  ASSERT_TRUE(printedKeys(output, config)) << output;
  const CameraOptions& c = config.camera;
  EXPECT_EQ(c.fx, 525.0);
  EXPECT_EQ(c.fy, 525.0);
  EXPECT_EQ(c.depth_z, 0.0);
  expectNear(keysAsCalibration(c, c.depth_fx, c.depth_fy),
             depthCamera({0.025, -0.003, 0.0}, {0.3, 0.5, -0.2}), 585.0);
}

}  // namespace
}  // namespace rgbdmap
