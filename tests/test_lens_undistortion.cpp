// The one lens undistortion of tracking, fusion and relocalisation: its depth resampling is the
// nearest-neighbour lookup cv::remap makes (tracking used cv::remap, fusion a table: both must
// keep their results), at full resolution and straight to a coarse pyramid level; and a level
// read from raw images averaged down to its resolution.
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

// Pyramid level 2's pinhole camera, pixel centres scaled as LevelCamera::halved() does.
cv::Matx33d quarterPinhole(const CameraIntrinsics& c) {
  const double cx = ((c.cx + 0.5) / 2 - 0.5 + 0.5) / 2 - 0.5;
  const double cy = ((c.cy + 0.5) / 2 - 0.5 + 0.5) / 2 - 0.5;
  return cv::Matx33d(c.fx / 4, 0, cx, 0, c.fy / 4, cy, 0, 0, 1);
}

// 2x2 means, twice: a raw image at the quarter level's resolution.
cv::Mat quarter(const cv::Mat& image) {
  cv::Mat half, out;
  cv::resize(image, half, cv::Size(image.cols / 2, image.rows / 2), 0, 0, cv::INTER_AREA);
  cv::resize(half, out, cv::Size(half.cols / 2, half.rows / 2), 0, 0, cv::INTER_AREA);
  return out;
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
  expectSameAsRemap(fr1(), quarterPinhole(fr1()), cv::Size(160, 120));
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

TEST(LensUndistortion, ALevelReadFromRawImagesAveragedDownSeesTheSamePlaces) {
  // A ramp averaged over blocks is the ramp at the blocks' centres, so a level resampled from
  // the quarter-size raw image must read the ramp where the full-resolution lookup does: the
  // pixel centres of the halved raw grid are placed right. (cv::remap interpolates at 1/32 of a
  // pixel: 1/8 of a raw pixel on the quarter grid, 0.04 of this ramp; a misplaced centre would
  // be off by 0.3 or more.)
  const CameraIntrinsics c = fr1();
  cv::Mat ramp(c.height, c.width, CV_32FC1);
  for (int v = 0; v < ramp.rows; ++v)
    for (int u = 0; u < ramp.cols; ++u) ramp.at<float>(v, u) = 0.3f * u + 0.2f * v;
  const cv::Size size(160, 120);
  cv::Mat expected, got;
  LensUndistortion(c, quarterPinhole(c), size).resampleImage(ramp, expected);
  const LensUndistortion lens(c, quarterPinhole(c), size, 2);
  lens.resampleImage(quarter(ramp), got);
  ASSERT_EQ(got.size(), size);
  // Compared where the raw position lies inside the raw image by a quarter-level pixel (outside,
  // each lookup repeats its own image's edge).
  cv::Mat map_x, map_y;
  cv::initUndistortRectifyMap(c.cameraMatrix(), c.distortion(), cv::noArray(), quarterPinhole(c),
                              size, CV_32FC1, map_x, map_y);
  int compared = 0;
  for (int v = 0; v < size.height; ++v)
    for (int u = 0; u < size.width; ++u) {
      const float x = map_x.at<float>(v, u), y = map_y.at<float>(v, u);
      if (x < 4 || y < 4 || x > c.width - 5 || y > c.height - 5) continue;
      ASSERT_NEAR(got.at<float>(v, u), expected.at<float>(v, u), 0.06) << u << "," << v;
      ++compared;
    }
  EXPECT_GT(compared, 15000);

  // Depth: the nearest sample of the quarter-size raw depth, indexed in that grid.
  const cv::Mat depth(c.height / 4, c.width / 4, CV_32FC1, cv::Scalar(2.0f));
  lens.resampleDepth(depth, got);
  int inside = 0;
  for (int i : lens.nearestRawPixel()) {
    ASSERT_LT(i, depth.rows * depth.cols);
    inside += i >= 0;
  }
  EXPECT_EQ(cv::countNonZero(got == 2.0f), inside);
  EXPECT_GT(inside, 15000);
}

TEST(LensUndistortion, ALevelReadFromRawImagesAveragedDownDoesNotAlias) {
  // Stripes one raw pixel wide: the quarter level cannot show them, and should show their mean,
  // not a pattern of its own (one bilinear sample of the full-resolution image per pixel
  // lands anywhere between a dark and a bright stripe).
  const CameraIntrinsics c = fr1();
  cv::Mat stripes(c.height, c.width, CV_8UC1);
  for (int v = 0; v < stripes.rows; ++v)
    for (int u = 0; u < stripes.cols; ++u) stripes.at<std::uint8_t>(v, u) = (u & 1) ? 200 : 40;
  cv::Mat straight, averaged, gray;
  LensUndistortion(c, quarterPinhole(c), cv::Size(160, 120)).resampleImage(stripes, straight);
  stripes.convertTo(gray, CV_32F);
  LensUndistortion(c, quarterPinhole(c), cv::Size(160, 120), 2)
      .resampleImage(quarter(gray), averaged);
  double lo, hi;
  cv::minMaxLoc(averaged, &lo, &hi);
  EXPECT_NEAR(lo, 120.0, 1.0);
  EXPECT_NEAR(hi, 120.0, 1.0);
  cv::minMaxLoc(straight, &lo, &hi);
  EXPECT_GT(hi - lo, 100.0);  // what the tracker saw before
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
