#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/capture/lens_undistortion.hpp"

namespace rgbdmap {

// Pinhole intrinsics of one pyramid level (no distortion: tracking works on the raw image).
struct LevelCamera {
  int width = 0;
  int height = 0;
  float fx = 0, fy = 0, cx = 0, cy = 0;
  LevelCamera halved() const;
};

// What the aligner samples from the frame being tracked, per pixel and interleaved so that one
// bilinear lookup reads everything: intensity, its x/y gradient, depth, its x/y gradient.
// Depth (and its gradient) is 0 where the depth or a neighbour needed for its gradient is
// missing or across a depth edge, which keeps the geometric term off there.
using PixelSample = Eigen::Matrix<float, 8, 1>;  // I, Ix, Iy, Z, Zx, Zy, unused, unused

struct PyramidLevel {
  LevelCamera camera;
  cv::Mat gray;   // CV_32FC1, grey levels 0..255
  cv::Mat depth;  // CV_32FC1, metres, 0 = missing
  std::vector<PixelSample, Eigen::aligned_allocator<PixelSample>> samples;  // row-major
};

// A frame as the tracker sees it: grey and depth at halving resolutions. Buffers are reused
// from frame to frame (build() writes in place).
class ImagePyramid {
 public:
  // Fills levels first..levels-1 from a BGR colour and a depth image in metres; depth outside
  // [min_depth, max_depth] counts as missing. With `undistort` and a camera with lens
  // distortion, level `first` is resampled to an ideal pinhole camera (so the 3-D points and the
  // projection agree everywhere in the image) from the raw images averaged down to its
  // resolution (grey: 2x2 means; depth: means of blocks that agree). Levels finer
  // than `first` are not to be read (they may be empty or hold what an earlier frame left).
  void build(const Frame& frame, const CameraIntrinsics& camera, int levels, int first,
             bool undistort, float min_depth, float max_depth);
  // Fills levels first..levels-1 from grey (CV_32FC1) and depth (CV_32FC1, metres, 0 = missing)
  // images that are already level `first`'s, with that level's camera; the finer levels are
  // left empty. (What a place keeps of its view is that level alone.)
  void buildFromLevel(const cv::Mat& gray, const cv::Mat& depth, const LevelCamera& camera,
                      int first, int levels);
  int levels() const { return static_cast<int>(levels_.size()); }
  const PyramidLevel& level(int i) const { return levels_[static_cast<std::size_t>(i)]; }
  // Fraction of full-resolution pixels with a usable depth.
  double depthFraction() const { return depth_fraction_; }

 private:
  // Levels from..to, each halved from the one before it.
  void halveFrom(int from, int to);
  // Levels first+1..levels-1 halved from level `first`, and every level's samples from `first`.
  void buildCoarser(int first);

  std::vector<PyramidLevel> levels_;
  double depth_fraction_ = 0.0;
  cv::Mat gray8_, raw_;                   // reused buffers
  cv::Mat raw_gray_[2], raw_depth_[2];    // the raw images averaged down, for undistortion
  std::optional<LensUndistortion> lens_;  // to the pinhole camera of level `first`
};

}  // namespace rgbdmap
