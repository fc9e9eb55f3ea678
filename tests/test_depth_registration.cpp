// Depth from a camera of its own: DepthRegistration moves it into the colour camera, and a run
// given the depth camera's pose (camera.depth_* keys) maps an unregistered sequence as well as a
// registered one would, where one without them does not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "rgbdmap/capture/depth_registration.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

// The depth camera 2.5 cm to the side of the colour one, a little lower and turned by 0.9 deg.
const Eigen::Vector3d kPosition(0.025, 0.003, -0.002);
const Eigen::Vector3d kRotationDeg(0.3, -0.8, 0.2);

CameraOptions unregisteredCamera() {
  CameraOptions camera;  // 640 x 480, f 525: the synthetic sequences' camera
  camera.depth_x = kPosition.x();
  camera.depth_y = kPosition.y();
  camera.depth_z = kPosition.z();
  const Eigen::Vector3d r = kRotationDeg * M_PI / 180.0;
  camera.depth_rx = r.x();
  camera.depth_ry = r.y();
  camera.depth_rz = r.z();
  return camera;
}

TEST(DepthRegistration, MovesTheDepthCamerasViewIntoTheColourCamera) {
  const CameraOptions camera = unregisteredCamera();
  ASSERT_FALSE(camera.depthRegistered());
  DepthRegistration registration(camera);
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  const SyntheticRenderer renderer(scene, camera);
  // Looking into a corner of the 5 x 4 m room from near its centre: walls, floor, furniture.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  pose.linear() = Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()) * pose.linear();
  pose.translation() = Eigen::Vector3d(-0.5, -0.3, 1.4);
  cv::Mat truth, depth, color, incidence, hits;
  renderer.render(pose, truth, color, incidence, hits);  // what the colour camera sees
  renderer.render(pose * registration.colorFromDepth(), depth, color, incidence, hits);

  // Unregistered, the depth camera's image is far from the colour camera's.
  const auto compare = [&truth](const cv::Mat& d, std::size_t& both, double& median) {
    std::vector<double> errors;
    for (int v = 0; v < truth.rows; ++v)
      for (int u = 0; u < truth.cols; ++u) {
        const float a = truth.at<float>(v, u), b = d.at<float>(v, u);
        if (a > 0 && b > 0) errors.push_back(std::abs(a - b));
      }
    both = errors.size();
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    median = errors.empty() ? 1e9 : errors[errors.size() / 2];
  };
  std::size_t both = 0;
  double before = 0, median = 0;
  compare(depth, both, before);
  const std::size_t pixels = static_cast<std::size_t>(truth.rows) * truth.cols;
  registration.apply(depth);
  compare(depth, both, median);
  EXPECT_GT(static_cast<double>(both), 0.96 * static_cast<double>(pixels));
  // Each depth pixel lands on the nearest colour pixel: on a slanted wall 2-3 m away the depth
  // changes by millimetres from one pixel to the next, so about a millimetre is left.
  EXPECT_LT(median, 0.0015) << "m";
  EXPECT_GT(before, 5 * median) << "m, before registration";
  // At depth edges a pixel may take the nearer or the farther surface; elsewhere it is exact.
  std::size_t far_off = 0;
  for (int v = 0; v < truth.rows; ++v)
    for (int u = 0; u < truth.cols; ++u) {
      const float a = truth.at<float>(v, u), b = depth.at<float>(v, u);
      if (a > 0 && b > 0 && std::abs(a - b) > 0.01f * a) ++far_off;
    }
  EXPECT_LT(static_cast<double>(far_off), 0.01 * static_cast<double>(pixels));
}

struct WalkRun {
  double ate_m = 0, precision = 0;
  std::string log;
};

WalkRun mapWalk(const std::string& sequence, const std::string& out, const std::string& keys) {
  WalkRun run;
  EXPECT_EQ(test::run(test::binary() + " --source tum:" + sequence + " --out " + out +
                          ".pcd --rate max -q --no-render --set pose.source=odometry" + keys,
                      &run.log),
            0)
      << run.log;
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " evaluate trajectory --estimate " + out +
                          "_trajectory.txt --groundtruth " + sequence + "/groundtruth.txt --json " +
                          out + "_ate.json",
                      &output),
            0)
      << output;
  run.ate_m = test::jsonNumber(test::readFile(out + "_ate.json"), "ate_rmse_m");
  EXPECT_EQ(test::run(test::binary() + " evaluate map " + out + ".pcd --scene " + sequence +
                          " --trajectory " + out + "_trajectory.txt --json " + out + "_map.json",
                      &output),
            0)
      << output;
  run.precision = test::jsonNumber(test::readFile(out + "_map.json"), "precision");
  return run;
}

TEST(DepthRegistration, AnUnregisteredWalkMapsAsWellAsARegisteredOneWithItsKeys) {
  const std::string walk = " --frames 180 --fps 15 --room 6x5x3 --path walk --loop-seconds 20";
  // A depth camera with a focal length of its own, as a Kinect's (580 px beside colour's 525).
  const std::string unregistered = test::sharedSynthetic(
      "walk_180_unregistered_f580",
      walk + " --depth-camera 0.025,0.003,-0.002,0.3,-0.8,0.2 --depth-focal 580");
  const Eigen::Vector3d r = kRotationDeg * M_PI / 180.0;
  const std::string keys =
      " --set camera.depth_fx=580 --set camera.depth_fy=580"
      " --set camera.depth_x=0.025 --set camera.depth_y=0.003"
      " --set camera.depth_z=-0.002 --set camera.depth_rx=" +
      std::to_string(r.x()) + " --set camera.depth_ry=" + std::to_string(r.y()) +
      " --set camera.depth_rz=" + std::to_string(r.z());
  const std::string dir = test::freshDir();
  const WalkRun with_keys = mapWalk(unregistered, dir + "/keys", keys);
  const WalkRun without = mapWalk(unregistered, dir + "/none", "");
  std::cout << "with the keys: ATE " << with_keys.ate_m * 100 << " cm, precision "
            << with_keys.precision << "; without: ATE " << without.ate_m * 100 << " cm, precision "
            << without.precision << "\n";
  // Measured on a 360-frame walk of an 8 x 6 m room: registered ATE 0.41 cm, P 0.9996;
  // unregistered with the keys 0.41 cm, P 0.9997; without them 2.1 cm, P 0.55.
  EXPECT_NE(with_keys.log.find("depth: its own camera, registered to colour on capture"),
            std::string::npos)
      << with_keys.log;
  EXPECT_LT(with_keys.ate_m, 0.005);
  EXPECT_GE(with_keys.precision, 0.995);
  EXPECT_GT(without.ate_m, 2 * with_keys.ate_m);
  EXPECT_LT(without.precision, 0.9);
}

}  // namespace
}  // namespace rgbdmap
