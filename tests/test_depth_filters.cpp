#include <gtest/gtest.h>

#include <random>

#include "rgbdmap/mapping/back_projector.hpp"
#include "rgbdmap/mapping/depth_filter.hpp"
#include "rgbdmap/mapping/depth_smoother.hpp"

namespace rgbdmap {
namespace {

// Depth of the plane n·X = d seen by a 525 px pinhole camera at pixel (u, v).
cv::Mat planeDepth(const Eigen::Vector3d& n, double d, int w = 64, int h = 48) {
  cv::Mat depth(h, w, CV_32FC1);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3d ray((u - w / 2.0) / 525.0, (v - h / 2.0) / 525.0, 1.0);
      depth.at<float>(v, u) = static_cast<float>(d / n.dot(ray));
    }
  return depth;
}

// `depth` with the Kinect's axial noise at each pixel's depth (kinectDepthSigma).
cv::Mat withKinectNoise(const cv::Mat& depth, unsigned seed) {
  std::mt19937 rng(seed);
  cv::Mat noisy = depth.clone();
  for (int v = 0; v < noisy.rows; ++v)
    for (int u = 0; u < noisy.cols; ++u) {
      std::normal_distribution<float> noise(0.0f, kinectDepthSigma(noisy.at<float>(v, u)));
      noisy.at<float>(v, u) += noise(rng);
    }
  return noisy;
}

TEST(DepthFilter, RangeDropsNearFarAndNan) {
  cv::Mat depth(4, 4, CV_32FC1, cv::Scalar(1.0f));
  depth.at<float>(0, 0) = 0.1f;
  depth.at<float>(1, 1) = 9.0f;
  depth.at<float>(2, 2) = std::nanf("");
  DepthFilter f;
  f.remove_flying_pixels = false;
  f.min_neighbours = 0;
  cv::Mat scratch;
  f.apply(depth, scratch);
  EXPECT_EQ(depth.at<float>(0, 0), 0.0f);
  EXPECT_EQ(depth.at<float>(1, 1), 0.0f);
  EXPECT_EQ(depth.at<float>(2, 2), 0.0f);
  EXPECT_EQ(depth.at<float>(3, 3), 1.0f);
}

TEST(DepthFilter, RemovesFlyingPixelsAtAStepButKeepsSlopes) {
  // Left half at 1 m, right half at 2 m: the pixels on both sides of the step are dropped.
  cv::Mat depth(10, 20, CV_32FC1, cv::Scalar(1.0f));
  depth(cv::Rect(10, 0, 10, 10)).setTo(2.0f);
  cv::Mat slope = planeDepth(Eigen::Vector3d(0.6, 0, -0.8).normalized(), -1.5, 20, 10);
  DepthFilter f;
  cv::Mat scratch;
  f.apply(depth, scratch);
  f.apply(slope, scratch);
  for (int v = 0; v < 10; ++v) {
    EXPECT_EQ(depth.at<float>(v, 9), 0.0f);
    EXPECT_EQ(depth.at<float>(v, 10), 0.0f);
    EXPECT_EQ(depth.at<float>(v, 8), 1.0f);
    EXPECT_EQ(depth.at<float>(v, 11), 2.0f);
  }
  EXPECT_EQ(cv::countNonZero(slope), slope.rows * slope.cols);  // a steep plane is not an edge
}

TEST(DepthFilter, RemovesIsolatedSpecks) {
  cv::Mat depth(9, 9, CV_32FC1, cv::Scalar(0.0f));
  depth(cv::Rect(0, 0, 5, 9)).setTo(1.5f);
  depth.at<float>(4, 7) = 1.5f;  // a lone measurement two pixels away from the surface
  DepthFilter f;
  cv::Mat scratch;
  f.apply(depth, scratch);
  EXPECT_EQ(depth.at<float>(4, 7), 0.0f);
  EXPECT_EQ(depth.at<float>(4, 2), 1.5f);
}

TEST(DepthSmoother, ExactOnPlanesAndReducesNoise) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, -1.0).normalized();
  const cv::Mat exact = planeDepth(n, -2.0);
  cv::Mat smoothed = exact.clone();
  DepthSmoother s;
  DepthSmoother::Buffers buffers;
  s.apply(smoothed, buffers);
  // Away from the border the window is full and symmetric: no bias on a plane.
  for (int v = 2; v < exact.rows - 2; ++v)
    for (int u = 2; u < exact.cols - 2; ++u)
      EXPECT_NEAR(smoothed.at<float>(v, u), exact.at<float>(v, u), 2e-5f) << u << "," << v;

  const cv::Mat noisy = withKinectNoise(exact, 1);
  cv::Mat denoised = noisy.clone();
  s.apply(denoised, buffers);
  double before = 0, after = 0;
  int count = 0;
  for (int v = 2; v < exact.rows - 2; ++v)
    for (int u = 2; u < exact.cols - 2; ++u, ++count) {
      before += std::pow(noisy.at<float>(v, u) - exact.at<float>(v, u), 2);
      after += std::pow(denoised.at<float>(v, u) - exact.at<float>(v, u), 2);
    }
  // 25 pixels averaged: the RMS error should drop by about 5x; ask for 3x.
  EXPECT_LT(std::sqrt(after / count), std::sqrt(before / count) / 3.0);
}

// A floor 4 m off, seen at 60 degrees from its normal, with the Kinect's noise (2.6 cm there): its
// windows spread by their slope and their noise more than 3% of the depth, so a smoother that
// drops unsmoothable pixels (as fusion's does) lost most of it; allowing for the noise keeps it.
TEST(DepthSmoother, KeepsFarNoisySlopesWhenItAllowsForTheNoise) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.0, -0.866, -0.5).normalized();
  const cv::Mat exact = planeDepth(n, -2.0);  // 4 m at the centre
  const cv::Mat noisy = withKinectNoise(exact, 3);
  const auto kept = [&](double noise_sigmas, double& rms) {
    DepthSmoother s;
    s.drop_unsmoothed = true;
    s.noise_sigmas = noise_sigmas;
    DepthSmoother::Buffers buffers;
    cv::Mat depth = noisy.clone();
    s.apply(depth, buffers);
    int inside = 0, left = 0;
    double squares = 0;
    for (int v = 2; v < depth.rows - 2; ++v)
      for (int u = 2; u < depth.cols - 2; ++u, ++inside) {
        if (depth.at<float>(v, u) <= 0.0f) continue;
        ++left;
        squares += std::pow(depth.at<float>(v, u) - exact.at<float>(v, u), 2);
      }
    rms = left > 0 ? std::sqrt(squares / left) : 0.0;
    return static_cast<double>(left) / inside;
  };
  double rms_strict = 0, rms_noise = 0;
  const double strict = kept(0.0, rms_strict), allowing = kept(4.0, rms_noise);
  EXPECT_LT(strict, 0.5);
  EXPECT_GT(allowing, 0.95);
  // What is kept is smoothed: a fifth of the noise, asked for within a third.
  EXPECT_LT(rms_noise, kinectDepthSigma(4.0f) / 3.0);
}

// Allowing for the noise does not blend a foreground into its background.
TEST(DepthSmoother, AllowingForNoiseStillKeepsEdges) {
  cv::Mat depth(10, 20, CV_32FC1, cv::Scalar(3.0f));
  depth(cv::Rect(10, 0, 10, 10)).setTo(3.6f);
  DepthSmoother s;
  s.noise_sigmas = 4.0;
  s.drop_unsmoothed = true;
  DepthSmoother::Buffers buffers;
  s.apply(depth, buffers);
  for (int v = 0; v < 10; ++v)
    for (int u = 0; u < 20; ++u) {
      const float d = depth.at<float>(v, u);
      if (u >= 8 && u < 12) {
        EXPECT_EQ(d, 0.0f) << u;  // windows across the step: dropped, not averaged
      } else if (d != 0.0f) {
        EXPECT_NEAR(d, u < 10 ? 3.0f : 3.6f, 1e-5f) << u;
      }
    }
}

TEST(DepthSmoother, DoesNotBlendAcrossEdges) {
  cv::Mat depth(10, 20, CV_32FC1, cv::Scalar(1.0f));
  depth(cv::Rect(10, 0, 10, 10)).setTo(2.0f);
  DepthSmoother s;
  DepthSmoother::Buffers buffers;
  s.apply(depth, buffers);
  for (int v = 0; v < 10; ++v)
    for (int u = 0; u < 20; ++u) EXPECT_EQ(depth.at<float>(v, u), u < 10 ? 1.0f : 2.0f);
}

}  // namespace
}  // namespace rgbdmap
