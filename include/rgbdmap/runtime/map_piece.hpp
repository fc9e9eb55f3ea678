#pragma once

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap {

// What a robot sends a fleet's merger of the map: each keyframe at half resolution (every
// second depth pixel, colour averaged over two by two), kept and sent as the KeyframeStore keeps
// images (inverse-depth PNG, colour at half that size). The merger fuses them into one TSDF at
// the poses its graph over all robots gives, so where two robots saw one wall there is one
// surface (their own maps, each at its robot's poses, gave two). At half resolution a pixel
// spans 8 mm at 2 m, under two of the map's voxels; a quarter of the bytes.
constexpr int kMapPieceStep = 2;

// The camera of a piece of `camera`'s keyframes (lens distortion is in normalised coordinates:
// it stays).
CameraIntrinsics mapPieceCamera(const CameraIntrinsics& camera);

// `keyframe` at the pieces' resolution, into `piece` (its buffers reused), with its timestamp,
// index, pose and anchor.
void makeMapPiece(const Frame& keyframe, Frame& piece);

}  // namespace rgbdmap
