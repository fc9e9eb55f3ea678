#pragma once

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap {

// What a robot sends a fleet's merger of the map: each keyframe at a quarter of its resolution,
// each pixel the average of a 4 x 4 block's measurements of one surface (a sixteenth of the
// pixels, a quarter of the noise), kept and sent as the KeyframeStore keeps images
// (inverse-depth PNG, colour at half that size). The merger fuses them into one TSDF at the poses
// its graph over all robots gives, so where two robots saw one wall there is one surface (their
// own maps, each at its robot's poses, gave two).
constexpr int kMapPieceStep = 4;

// The camera of a piece of `camera`'s keyframes (lens distortion is in normalised coordinates:
// it stays).
CameraIntrinsics mapPieceCamera(const CameraIntrinsics& camera);

// `keyframe` at the pieces' resolution, into `piece` (its buffers reused), with its timestamp,
// index, pose and anchor. Depth within `same_surface` (relative) of a block's centre pixel is
// taken as the same surface.
void makeMapPiece(const Frame& keyframe, Frame& piece, double same_surface = 0.03);

}  // namespace rgbdmap
