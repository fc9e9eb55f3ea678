// Finding the floor in one keyframe's depth: a rendered view of a floor, a wall and a table top
// with the Kinect's depth noise.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "rgbdmap/slam/keyframe_floor.hpp"

namespace rgbdmap {
namespace {

constexpr double kHeight = 1.4;  // m, the camera over the floor

// Camera-to-world: world z up, the camera at kHeight looking along +x, pitched down by `pitch`
// and rolled by `roll`.
Eigen::Isometry3d cameraPose(double pitch, double roll) {
  Eigen::Matrix3d level;
  level.col(0) = -Eigen::Vector3d::UnitY();  // the camera's x (right) in the world
  level.col(1) = -Eigen::Vector3d::UnitZ();  // its y (down)
  level.col(2) = Eigen::Vector3d::UnitX();   // its z (ahead)
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = level * Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitX()).toRotationMatrix() *
                  Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(0, 0, kHeight);
  return pose;
}

// Depth along each pixel's ray to the nearest of: the floor (z = 0), a wall 3.5 m ahead, and a
// table top 0.75 m high over x 1.2..2.2, y -0.6..0.6 (`table`), with noise sigma(z).
cv::Mat render(const CameraIntrinsics& c, const Eigen::Isometry3d& pose, bool table,
               std::uint32_t seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  cv::Mat depth(c.height, c.width, CV_32FC1, cv::Scalar(0));
  const Eigen::Vector3d o = pose.translation();
  for (int v = 0; v < c.height; ++v) {
    for (int u = 0; u < c.width; ++u) {
      const Eigen::Vector3d ray_c((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);  // z = 1
      const Eigen::Vector3d ray = pose.linear() * ray_c;
      double s = std::numeric_limits<double>::infinity();  // along ray: depth z = s
      if (ray.z() < 0) s = std::min(s, -o.z() / ray.z());
      if (ray.x() > 0) s = std::min(s, (3.5 - o.x()) / ray.x());
      if (table && ray.z() < 0) {
        const double t = (0.75 - o.z()) / ray.z();
        const Eigen::Vector3d p = o + t * ray;
        if (p.x() >= 1.2 && p.x() <= 2.2 && std::abs(p.y()) <= 0.6) s = std::min(s, t);
      }
      if (!std::isfinite(s) || s > 4.5) continue;
      const double sigma = 0.0012 + 0.0019 * (s - 0.4) * (s - 0.4);
      depth.at<float>(v, u) = static_cast<float>(s + sigma * unit(random));
    }
  }
  return depth;
}

// The floor as a camera at `pose` sees it.
CameraPlane floorIn(const Eigen::Isometry3d& pose) {
  CameraPlane p;
  p.normal = pose.linear().transpose() * Eigen::Vector3d::UnitZ();
  p.distance = -pose.translation().z();
  return p;
}

double degreesBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

TEST(KeyframeFloor, DiscoversTheFloorNotTheTableAbove) {
  const CameraIntrinsics camera;
  KeyframeFloor finder(camera, 0.3, 4.0, KeyframeFloor::Config{});
  for (const auto& [pitch, roll] : {std::pair{0.35, 0.0}, std::pair{0.25, 0.1}}) {
    const Eigen::Isometry3d pose = cameraPose(pitch, roll);
    const cv::Mat depth = render(camera, pose, true, 3);
    // The guess of up: the camera's -y, as for a camera held upright, here 15-20 deg off.
    const auto found = finder.discover(depth, -Eigen::Vector3d::UnitY());
    ASSERT_TRUE(found) << "pitch " << pitch;
    const CameraPlane truth = floorIn(pose);
    EXPECT_LT(degreesBetween(found->normal, truth.normal), 0.15);
    EXPECT_NEAR(found->distance, truth.distance, 0.003);  // not the table's -0.65
    EXPECT_GT(found->extent, 0.3);
  }
}

TEST(KeyframeFloor, RefitsAGuessThatIsOffByCentimetresAndADegree) {
  const CameraIntrinsics camera;
  KeyframeFloor finder(camera, 0.3, 4.0, KeyframeFloor::Config{});
  const Eigen::Isometry3d pose = cameraPose(0.3, 0.05);
  const cv::Mat depth = render(camera, pose, false, 5);
  const CameraPlane truth = floorIn(pose);
  CameraPlane guess = truth;
  guess.normal = (Eigen::AngleAxisd(0.015, Eigen::Vector3d::UnitX()) * truth.normal).normalized();
  guess.distance += 0.03;
  const auto found = finder.near(depth, guess);
  ASSERT_TRUE(found);
  EXPECT_LT(degreesBetween(found->normal, truth.normal), 0.15);
  EXPECT_NEAR(found->distance, truth.distance, 0.003);
}

TEST(KeyframeFloor, NoFloorWhereTheViewShowsNone) {
  const CameraIntrinsics camera;
  KeyframeFloor finder(camera, 0.3, 4.0, KeyframeFloor::Config{});
  // Looking up at the wall: no floor in view.
  const Eigen::Isometry3d pose = cameraPose(-0.45, 0.0);
  const cv::Mat depth = render(camera, pose, false, 7);
  EXPECT_FALSE(finder.discover(depth, -Eigen::Vector3d::UnitY()));
  EXPECT_FALSE(finder.near(depth, floorIn(pose)));
  // A guess 20 cm off (a different level) finds nothing either, though the floor is in view.
  const Eigen::Isometry3d down = cameraPose(0.35, 0.0);
  CameraPlane wrong = floorIn(down);
  wrong.distance += 0.2;
  EXPECT_FALSE(finder.near(render(camera, down, false, 9), wrong));
  // An empty or mis-sized image is no floor, not a crash.
  EXPECT_FALSE(finder.discover(cv::Mat(), -Eigen::Vector3d::UnitY()));
  EXPECT_FALSE(finder.near(cv::Mat(10, 10, CV_32FC1, cv::Scalar(1.0f)), floorIn(down)));
}

}  // namespace
}  // namespace rgbdmap
