// The one lens undistortion of tracking, fusion and relocalisation: its depth resampling is the
// nearest-neighbour lookup cv::remap makes (tracking used cv::remap, fusion a table: both must
// keep their results), at full resolution and straight to a coarse pyramid level.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/capture/lens_undistortion.hpp"

namespace rgbdmap {
namespace {

CameraIntrinsics fr1() {  // TUM freiburg1: strong radial distortion
  CameraIntrinsics c;
  c.fx = 517.3;
  c.fy = 516.5;
  c.cx = 318.6;
  c.cy = 255.3;
  c.k1 = 0.2624;
  c.k2 = -0.9531;
  c.p1 = -0.0054;
  c.p2 = 0.0026;
  c.k3 = 1.1633;
  return c;
}

cv::Mat randomDepth(const CameraIntrinsics& c) {
  cv::Mat depth(c.height, c.width, CV_32FC1);
  std::mt19937 random(7);
  std::uniform_real_distribution<float> metres(0.5f, 4.0f);
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) depth.at<float>(v, u) = metres(random);
  return depth;
}

void expectSameAsRemap(const CameraIntrinsics& c, const cv::Matx33d& pinhole, cv::Size size) {
  cv::Mat map_x, map_y, expected, got, pooled;
  cv::initUndistortRectifyMap(c.cameraMatrix(), c.distortion(), cv::noArray(), pinhole, size,
                              CV_32FC1, map_x, map_y);
  const cv::Mat depth = randomDepth(c);
  cv::remap(depth, expected, map_x, map_y, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  const LensUndistortion lens(c, pinhole, size);
  lens.resampleDepth(depth, got);
  WorkerPool pool(3);
  lens.resampleDepth(depth, pooled, &pool);
  ASSERT_EQ(got.size(), size);
  EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(pooled, expected, cv::NORM_INF), 0.0);
  int outside = 0;
  for (int i : lens.nearestRawPixel()) outside += i < 0;
  EXPECT_EQ(outside, cv::countNonZero(expected == 0));
}

TEST(LensUndistortion, DepthIsRemapsNearestSampleAtFullResolution) {
  expectSameAsRemap(fr1(), fr1().cameraMatrix(), cv::Size(640, 480));
}

TEST(LensUndistortion, DepthIsRemapsNearestSampleAtAQuarterLevel) {
  // Pyramid level 2 of the tracker: pixel centres scaled as LevelCamera::halved() does.
  const CameraIntrinsics c = fr1();
  const double cx = ((c.cx + 0.5) / 2 - 0.5 + 0.5) / 2 - 0.5;
  const double cy = ((c.cy + 0.5) / 2 - 0.5 + 0.5) / 2 - 0.5;
  expectSameAsRemap(c, cv::Matx33d(c.fx / 4, 0, cx, 0, c.fy / 4, cy, 0, 0, 1), cv::Size(160, 120));
}

TEST(LensUndistortion, ImageIsRemappedBilinearly) {
  const CameraIntrinsics c = fr1();
  cv::Mat grey(c.height, c.width, CV_8UC1), expected, got, map_x, map_y;
  cv::randu(grey, 0, 256);
  cv::initUndistortRectifyMap(c.cameraMatrix(), c.distortion(), cv::noArray(), c.cameraMatrix(),
                              grey.size(), CV_32FC1, map_x, map_y);
  cv::remap(grey, expected, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  LensUndistortion(c).resampleImage(grey, got);
  EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0);
}

TEST(LensUndistortion, RaysUndoTheDistortionOfProjectedPoints) {
  const CameraIntrinsics c = fr1();
  const std::vector<cv::Point3f> points = {{0, 0, 1}, {0.3f, -0.2f, 1.5f}, {-0.5f, 0.35f, 2}};
  std::vector<cv::Point2f> pixels, rays;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), c.cameraMatrix(),
                    c.distortion(), pixels);
  LensUndistortion::rays(c, pixels, rays);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_NEAR(rays[i].x, points[i].x / points[i].z, 1e-3);
    EXPECT_NEAR(rays[i].y, points[i].y / points[i].z, 1e-3);
  }
}

}  // namespace
}  // namespace rgbdmap
