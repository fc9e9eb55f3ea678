// The depth filter and smoother as the keyframe integrator uses them (reading the frame, not a
// copy; unsmoothable pixels dropped), on images with holes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "rgbdmap/mapping/depth_filter.hpp"
#include "rgbdmap/mapping/depth_smoother.hpp"

namespace rgbdmap {
namespace {

// A fronto-parallel wall at 2 m with a square hole (no depth) in the middle.
cv::Mat wallWithHole() {
  cv::Mat depth(40, 60, CV_32FC1, cv::Scalar(2.0f));
  depth(cv::Rect(25, 15, 10, 10)).setTo(0.0f);
  return depth;
}

TEST(FusionFilters, SmoothingNextToHolesStaysFinite) {
  // Missing pixels must count as nothing (1/0 is inf).
  cv::Mat depth = wallWithHole();
  DepthSmoother s;
  DepthSmoother::Buffers buffers;
  s.apply(depth, buffers);
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const float z = depth.at<float>(v, u);
      ASSERT_TRUE(std::isfinite(z)) << u << "," << v;
      if (z != 0.0f) {
        EXPECT_NEAR(z, 2.0f, 1e-5f) << u << "," << v;
      }
    }
  EXPECT_EQ(depth.at<float>(20, 30), 0.0f);  // the hole stays a hole
}

TEST(FusionFilters, DropUnsmoothedClearsOnlyPixelsWithoutAFullEnoughWindow) {
  cv::Mat kept = wallWithHole(), dropped = wallWithHole();
  DepthSmoother s;
  DepthSmoother::Buffers buffers;
  s.apply(kept, buffers);
  s.drop_unsmoothed = true;
  s.apply(dropped, buffers);
  // Far from the hole and the border: smoothed in both.
  EXPECT_NEAR(dropped.at<float>(5, 5), 2.0f, 1e-5f);
  // The image corner has a quarter window (9 of 25 pixels): kept as measured, or dropped.
  EXPECT_EQ(kept.at<float>(0, 0), 2.0f);
  EXPECT_EQ(dropped.at<float>(0, 0), 0.0f);
  // A step edge: both sides are dropped within the window radius of it.
  cv::Mat step(10, 20, CV_32FC1, cv::Scalar(1.0f));
  step(cv::Rect(10, 0, 10, 10)).setTo(2.0f);
  s.apply(step, buffers);
  EXPECT_EQ(step.at<float>(5, 9), 0.0f);
  EXPECT_EQ(step.at<float>(5, 10), 0.0f);
  EXPECT_EQ(step.at<float>(5, 5), 1.0f);
}

TEST(FusionFilters, FilterFromTheFrameEqualsFilterInPlace) {
  cv::Mat frame = wallWithHole();
  frame.at<float>(5, 5) = 3.0f;   // a flying pixel
  frame.at<float>(0, 59) = 9.0f;  // out of range, at the border
  frame.at<float>(39, 0) = NAN;   // invalid
  DepthFilter filter;
  cv::Mat in_place = frame.clone(), out, scratch;
  filter.apply(in_place, scratch);
  const cv::Mat before = frame.clone();
  filter.apply(frame, out, scratch);
  EXPECT_EQ(std::memcmp(frame.data, before.data, frame.total() * frame.elemSize()), 0)
      << "the input was modified";
  EXPECT_EQ(cv::countNonZero(out != in_place), 0);
  EXPECT_EQ(out.at<float>(5, 5), 0.0f);
  EXPECT_EQ(out.at<float>(0, 59), 0.0f);
  EXPECT_EQ(out.at<float>(39, 0), 0.0f);
  EXPECT_EQ(out.at<float>(30, 30), 2.0f);
}

}  // namespace
}  // namespace rgbdmap
