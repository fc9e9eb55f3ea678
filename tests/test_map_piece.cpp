// A map piece (what a robot sends a fleet's merger of each keyframe): on exact geometry, each
// pixel is the surface its block of the keyframe sees, along the ray of the piece's camera, and a
// block across an edge is not averaged into a point on neither side.

#include <gtest/gtest.h>

#include <cmath>

#include "rgbdmap/sessions/map_piece.hpp"

namespace rgbdmap {
namespace {

// The depth of a slanted plane (n . X = d in the camera frame) seen by `camera` at pixel (u, v).
double planeDepth(const CameraIntrinsics& camera, const Eigen::Vector3d& n, double d, double u,
                  double v) {
  const Eigen::Vector3d ray((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
  return d / n.dot(ray);
}

TEST(MapPiece, EachPixelIsTheSurfaceAlongItsRayAndEdgesAreNotBlurred) {
  CameraIntrinsics camera;  // 640 x 480, fx 525
  camera.cx = 318.6;
  camera.cy = 241.2;
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  Frame keyframe;
  keyframe.depth.create(camera.height, camera.width, CV_32FC1);
  keyframe.color = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(10, 20, 30));
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u)
      // A plane about 2 m away; on the right of column 400 a wall at 3 m (an edge).
      keyframe.depth.at<float>(v, u) =
          u >= 402 ? 3.0f : static_cast<float>(planeDepth(camera, n, 2.0, u, v));
  keyframe.index = 7;
  keyframe.anchor = 3;
  keyframe.pose.translation() = Eigen::Vector3d(1, 2, 3);

  Frame piece;
  makeMapPiece(keyframe, piece);
  const CameraIntrinsics small = mapPieceCamera(camera);
  ASSERT_EQ(piece.depth.cols, small.width);
  ASSERT_EQ(piece.depth.rows, small.height);
  EXPECT_EQ(small.width, camera.width / kMapPieceStep);
  EXPECT_EQ(piece.index, 7u);
  EXPECT_EQ(piece.anchor, 3);
  EXPECT_TRUE(piece.pose.isApprox(keyframe.pose));
  double worst = 0.0;
  int edge_blocks = 0;
  for (int v = 0; v < piece.depth.rows; ++v)
    for (int u = 0; u < piece.depth.cols; ++u) {
      const float z = piece.depth.at<float>(v, u);
      ASSERT_GT(z, 0.0f) << u << "," << v;
      // Every point lies on one of the two surfaces, where the piece's camera looks.
      const double plane = planeDepth(small, n, 2.0, u, v);
      const double error = std::min(std::abs(z - plane), std::abs(z - 3.0));
      worst = std::max(worst, error);
      if ((u + 1) * kMapPieceStep > 402 && u * kMapPieceStep < 402) ++edge_blocks;
    }
  // A block's average of inverse depth is the plane's inverse depth at its centre: to rounding.
  EXPECT_LT(worst, 1e-4);
  EXPECT_GT(edge_blocks, 0);
  EXPECT_EQ(piece.color.at<cv::Vec3b>(10, 10), cv::Vec3b(10, 20, 30));
}

TEST(MapPiece, ABlockWithTooFewMeasurementsIsLeftOut) {
  Frame keyframe;
  keyframe.depth = cv::Mat(480, 640, CV_32FC1, cv::Scalar(0.0f));
  keyframe.color = cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0));
  // Three measurements in the first block (a speck), a full second block.
  for (int i = 0; i < 3; ++i) keyframe.depth.at<float>(i, 0) = 1.0f;
  for (int y = 0; y < kMapPieceStep; ++y)
    for (int x = kMapPieceStep; x < 2 * kMapPieceStep; ++x) keyframe.depth.at<float>(y, x) = 1.5f;
  Frame piece;
  makeMapPiece(keyframe, piece);
  EXPECT_EQ(piece.depth.at<float>(0, 0), 0.0f);
  EXPECT_NEAR(piece.depth.at<float>(0, 1), 1.5f, 1e-6);
  EXPECT_EQ(cv::countNonZero(piece.depth), 1);
}

}  // namespace
}  // namespace rgbdmap
