#include "rgbdmap/sessions/map_piece.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace rgbdmap {

CameraIntrinsics mapPieceCamera(const CameraIntrinsics& camera) {
  CameraIntrinsics piece = camera;
  // Pixel (u, v) of the piece is the block of pixels from (4u, 4v) on: the ray of its centre.
  constexpr double kCentre = (kMapPieceStep - 1) / 2.0;
  piece.width = camera.width / kMapPieceStep;
  piece.height = camera.height / kMapPieceStep;
  piece.fx = camera.fx / kMapPieceStep;
  piece.fy = camera.fy / kMapPieceStep;
  piece.cx = (camera.cx - kCentre) / kMapPieceStep;
  piece.cy = (camera.cy - kCentre) / kMapPieceStep;
  return piece;
}

void makeMapPiece(const Frame& keyframe, Frame& piece, double same_surface) {
  constexpr int kStep = kMapPieceStep;
  const cv::Size size(keyframe.depth.cols / kStep, keyframe.depth.rows / kStep);
  piece.depth.create(size, CV_32FC1);
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) {
      // The block's measurements on the surface its centre pixel sees (an average across an
      // edge would be a point on neither side), averaged in inverse depth: on a plane that is
      // the inverse depth of the block's centre.
      float reference = keyframe.depth.at<float>(v * kStep + kStep / 2, u * kStep + kStep / 2);
      float sum = 0.0f;
      int count = 0;
      for (int pass = 0; pass < 2 && count == 0; ++pass) {
        for (int y = v * kStep; y < (v + 1) * kStep; ++y) {
          const float* row = keyframe.depth.ptr<float>(y);
          for (int x = u * kStep; x < (u + 1) * kStep; ++x) {
            const float z = row[x];
            if (!(z > 0.0f)) continue;
            if (!(reference > 0.0f)) reference = z;  // no centre measurement: the first
            if (std::abs(z - reference) > static_cast<float>(same_surface) * reference) continue;
            sum += 1.0f / z;
            ++count;
          }
        }
      }
      // Fewer than a quarter of the block on one surface: a speck or an edge, left out.
      piece.depth.at<float>(v, u) = count * 4 >= kStep * kStep ? count / sum : 0.0f;
    }
  }
  cv::resize(keyframe.color, piece.color, size, 0.0, 0.0, cv::INTER_AREA);
  piece.index = keyframe.index;
  piece.timestamp = keyframe.timestamp;
  piece.has_pose = keyframe.has_pose;
  piece.pose = keyframe.pose;
  piece.anchor = keyframe.anchor;
  piece.origin = keyframe.origin;
}

}  // namespace rgbdmap
