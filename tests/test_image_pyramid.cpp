// The tracker's pyramid starts at a coarse level. Built there straight from the full-resolution
// images, it must hold what halving the images level by level gives, to the bit: the tracker's
// poses (and every map made from them) must not depend on which way it was built.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <random>

#include "rgbdmap/tracking/image_pyramid.hpp"

namespace {

using namespace rgbdmap;

// A frame of random colour with depth in metres, some of it missing and some of it in steps
// (edges that halving must not average across).
Frame randomFrame(int width, int height) {
  Frame frame;
  frame.color.create(height, width, CV_8UC3);
  frame.depth.create(height, width, CV_32FC1);
  std::mt19937 random(11);
  std::uniform_int_distribution<int> grey(0, 255), missing(0, 19);
  std::uniform_real_distribution<float> depth(0.6f, 4.5f);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const cv::Vec3b colour(static_cast<uchar>(grey(random)), static_cast<uchar>(grey(random)),
                             static_cast<uchar>(grey(random)));
      frame.color.at<cv::Vec3b>(y, x) = colour;
      const float step = (x / 37 + y / 23) % 2 ? 1.0f : 0.0f;
      frame.depth.at<float>(y, x) = missing(random) == 0 ? 0.0f : depth(random) * 0.01f + 1 + step;
    }
  return frame;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

TEST(ImagePyramid, ACoarseFirstLevelHoldsWhatHalvingEachLevelGives) {
  const Frame frame = randomFrame(640, 480);
  const CameraIntrinsics camera;  // no lens distortion: the images are halved as they are
  ImagePyramid from_full, level_by_level;
  from_full.build(frame, camera, 4, 2, true, 0.4f, 5.0f);
  level_by_level.build(frame, camera, 4, 0, true, 0.4f, 5.0f);
  for (int l = 2; l < 4; ++l) {
    SCOPED_TRACE(l);
    const PyramidLevel& a = from_full.level(l);
    const PyramidLevel& b = level_by_level.level(l);
    EXPECT_TRUE(same(a.gray, b.gray));
    EXPECT_TRUE(same(a.depth, b.depth));
    EXPECT_EQ(a.camera.width, b.camera.width);
    EXPECT_EQ(a.camera.fx, b.camera.fx);
    EXPECT_EQ(a.camera.cx, b.camera.cx);
    ASSERT_EQ(a.samples.size(), b.samples.size());
    for (std::size_t i = 0; i < a.samples.size(); ++i)
      ASSERT_EQ(a.samples[i], b.samples[i]) << "sample " << i;
  }
  EXPECT_GT(cv::countNonZero(from_full.level(2).depth), 0);
  EXPECT_LT(cv::countNonZero(from_full.level(2).depth), 160 * 120);  // the edges were kept out
}

TEST(ImagePyramid, AnOddSizedImageIsHalvedLevelByLevel) {
  // 2x2 blocks do not tile an odd image: cv::resize's area average then weighs partial pixels,
  // and the pyramid takes the same way as one built level by level.
  const Frame frame = randomFrame(321, 241);
  CameraIntrinsics camera;
  camera.width = 321;
  camera.height = 241;
  ImagePyramid from_full, level_by_level;
  from_full.build(frame, camera, 3, 1, true, 0.4f, 5.0f);
  level_by_level.build(frame, camera, 3, 0, true, 0.4f, 5.0f);
  EXPECT_TRUE(same(from_full.level(1).gray, level_by_level.level(1).gray));
  EXPECT_TRUE(same(from_full.level(2).gray, level_by_level.level(2).gray));
}

}  // namespace
