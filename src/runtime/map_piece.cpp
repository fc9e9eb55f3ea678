#include "rgbdmap/runtime/map_piece.hpp"

#include <opencv2/imgproc.hpp>

namespace rgbdmap {

CameraIntrinsics mapPieceCamera(const CameraIntrinsics& camera) {
  CameraIntrinsics piece = camera;
  // Pixel (u, v) of the piece is pixel (2u, 2v) of the keyframe: the same ray.
  piece.width = camera.width / kMapPieceStep;
  piece.height = camera.height / kMapPieceStep;
  piece.fx = camera.fx / kMapPieceStep;
  piece.fy = camera.fy / kMapPieceStep;
  piece.cx = camera.cx / kMapPieceStep;
  piece.cy = camera.cy / kMapPieceStep;
  return piece;
}

void makeMapPiece(const Frame& keyframe, Frame& piece) {
  const cv::Size size(keyframe.depth.cols / kMapPieceStep, keyframe.depth.rows / kMapPieceStep);
  // Depth sampled, not averaged: an average across an edge is a point on neither side.
  piece.depth.create(size, CV_32FC1);
  for (int v = 0; v < size.height; ++v) {
    const float* in = keyframe.depth.ptr<float>(v * kMapPieceStep);
    float* out = piece.depth.ptr<float>(v);
    for (int u = 0; u < size.width; ++u) out[u] = in[u * kMapPieceStep];
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
