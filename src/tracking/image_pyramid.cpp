#include "rgbdmap/tracking/image_pyramid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/base/vector_clones.hpp"

namespace rgbdmap {
namespace {

// Mean of the valid depths of each 2x2 block, if they agree (a block straddling a depth edge
// would otherwise invent a surface between the two). Written without branches (a missing depth
// adds 0 to the sum, which is exact), so that the loop is vectorised: at full resolution it was
// a twentieth of tracking's time.
RGBDMAP_VECTOR_CLONES void halveDepth(const cv::Mat& in, cv::Mat& out) {
  out.create(in.rows / 2, in.cols / 2, CV_32FC1);
  for (int y = 0; y < out.rows; ++y) {
    const float* a = in.ptr<float>(2 * y);
    const float* b = in.ptr<float>(2 * y + 1);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x) {
      const float d[4] = {a[2 * x], a[2 * x + 1], b[2 * x], b[2 * x + 1]};
      float sum = 0, lo = 1e9f, hi = 0, n = 0;
      for (float v : d) {
        const bool valid = v > 0;  // also false for NaN
        sum += valid ? v : 0.0f;
        n += valid ? 1.0f : 0.0f;
        lo = std::min(lo, valid ? v : 1e9f);
        hi = std::max(hi, valid ? v : 0.0f);
      }
      o[x] = (n > 0 && hi - lo < 0.05f * lo) ? sum / std::max(n, 1.0f) : 0.0f;
    }
  }
}

// Mean of each 2x2 block of an 8-bit grey image, as floats: what cv::resize's INTER_AREA gives
// for the image converted to floats (the sums of whole grey levels are exact either way), without
// converting the full-resolution image first.
void halveGray(const cv::Mat& in, cv::Mat& out) {
  out.create(in.rows / 2, in.cols / 2, CV_32FC1);
  for (int y = 0; y < out.rows; ++y) {
    const std::uint8_t* a = in.ptr<std::uint8_t>(2 * y);
    const std::uint8_t* b = in.ptr<std::uint8_t>(2 * y + 1);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x)
      o[x] = static_cast<float>(a[2 * x] + a[2 * x + 1] + b[2 * x] + b[2 * x + 1]) * 0.25f;
  }
}

// Grey (CV_32FC1: 2x2 means, INTER_AREA) and depth (halveDepth) at half the resolution.
void halveImages(const cv::Mat& gray, const cv::Mat& depth, cv::Mat& half_gray,
                 cv::Mat& half_depth) {
  cv::resize(gray, half_gray, cv::Size(gray.cols / 2, gray.rows / 2), 0, 0, cv::INTER_AREA);
  halveDepth(depth, half_depth);
}

// Depth gradient by central differences; 0 where a neighbour is missing or across an edge.
bool depthGradient(const float* up, const float* row, const float* down, int x, float& zx,
                   float& zy) {
  const float z = row[x], l = row[x - 1], r = row[x + 1], u = up[x], d = down[x];
  if (z <= 0 || l <= 0 || r <= 0 || u <= 0 || d <= 0) return false;
  const float edge = 0.04f * z;
  if (std::abs(r - l) > edge || std::abs(d - u) > edge) return false;
  zx = 0.5f * (r - l);
  zy = 0.5f * (d - u);
  return true;
}

void computeSamples(PyramidLevel& level) {
  const int w = level.gray.cols, h = level.gray.rows;
  level.samples.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h),
                       PixelSample::Zero());
  for (int y = 1; y + 1 < h; ++y) {
    const float* g0 = level.gray.ptr<float>(y - 1);
    const float* g1 = level.gray.ptr<float>(y);
    const float* g2 = level.gray.ptr<float>(y + 1);
    const float* d0 = level.depth.ptr<float>(y - 1);
    const float* d1 = level.depth.ptr<float>(y);
    const float* d2 = level.depth.ptr<float>(y + 1);
    PixelSample* s = &level.samples[static_cast<std::size_t>(y) * static_cast<std::size_t>(w)];
    for (int x = 1; x + 1 < w; ++x) {
      PixelSample& p = s[x];
      p[0] = g1[x];
      p[1] = 0.5f * (g1[x + 1] - g1[x - 1]);
      p[2] = 0.5f * (g2[x] - g0[x]);
      float zx = 0, zy = 0;
      if (depthGradient(d0, d1, d2, x, zx, zy)) {
        p[3] = d1[x];
        p[4] = zx;
        p[5] = zy;
      }
    }
  }
}

}  // namespace

LevelCamera LevelCamera::halved() const {
  // Pixel centres: x_half = (x + 0.5) / 2 - 0.5.
  return {width / 2, height / 2, fx / 2, fy / 2, (cx + 0.5f) / 2 - 0.5f, (cy + 0.5f) / 2 - 0.5f};
}

void ImagePyramid::build(const Frame& frame, const CameraIntrinsics& camera, int levels, int first,
                         bool undistort, float min_depth, float max_depth) {
  levels_.resize(static_cast<std::size_t>(levels));
  LevelCamera full{frame.depth.cols,
                   frame.depth.rows,
                   static_cast<float>(camera.fx),
                   static_cast<float>(camera.fy),
                   static_cast<float>(camera.cx),
                   static_cast<float>(camera.cy)};
  LevelCamera at_first = full;
  for (int i = 0; i < first; ++i) at_first = at_first.halved();
  cv::cvtColor(frame.color, gray8_, cv::COLOR_BGR2GRAY);
  PyramidLevel& base = levels_[static_cast<std::size_t>(first)];
  base.camera = at_first;
  if (undistort && camera.hasDistortion()) {
    // Resampled from raw images averaged down to the level's resolution: one bilinear sample of
    // the full-resolution image per pixel aliases (fine texture turns into noise that moves with
    // the camera), and one raw depth sample keeps all its noise.
    const bool halvable = full.width % (1 << first) == 0 && full.height % (1 << first) == 0;
    const int raw_level = halvable ? first : 0;
    const cv::Size size(at_first.width, at_first.height);
    if (!lens_ || lens_->size() != size) {
      const cv::Matx33d K(at_first.fx, 0, at_first.cx, 0, at_first.fy, at_first.cy, 0, 0, 1);
      lens_.emplace(camera, K, size, raw_level);
    }
    if (raw_level > 0) {
      halveGray(gray8_, raw_gray_[0]);
      halveDepth(frame.depth, raw_depth_[0]);
      for (int i = 1; i < raw_level; ++i) {
        halveImages(raw_gray_[0], raw_depth_[0], raw_gray_[1], raw_depth_[1]);
        std::swap(raw_gray_[0], raw_gray_[1]);
        std::swap(raw_depth_[0], raw_depth_[1]);
      }
      lens_->resampleImage(raw_gray_[0], base.gray);
      lens_->resampleDepth(raw_depth_[0], base.depth);
    } else {
      lens_->resampleImage(gray8_, raw_);
      raw_.convertTo(base.gray, CV_32F);
      lens_->resampleDepth(frame.depth, base.depth);
    }
  } else if (first > 0 && full.width % 2 == 0 && full.height % 2 == 0) {
    // Level 1 straight from the full-resolution images: the finer level is never aligned, and
    // converting and copying it took a twentieth of a frame's tracking.
    PyramidLevel& level1 = levels_[1];
    level1.camera = full.halved();
    halveGray(gray8_, level1.gray);
    halveDepth(frame.depth, level1.depth);
    halveFrom(2, first);
  } else {
    PyramidLevel& level0 = levels_[0];
    level0.camera = full;
    gray8_.convertTo(level0.gray, CV_32F);
    frame.depth.copyTo(level0.depth);
    halveFrom(1, first);
  }
  int valid = 0;
  for (int y = 0; y < base.depth.rows; ++y) {
    float* d = base.depth.ptr<float>(y);
    for (int x = 0; x < base.depth.cols; ++x) {
      const bool ok = d[x] >= min_depth && d[x] <= max_depth;  // also false for NaN
      if (!ok) d[x] = 0.0f;
      valid += ok;
    }
  }
  depth_fraction_ = static_cast<double>(valid) / static_cast<double>(base.depth.total());
  buildCoarser(first);
}

void ImagePyramid::buildFromLevel(const cv::Mat& gray, const cv::Mat& depth,
                                  const LevelCamera& camera, int first, int levels) {
  levels_.resize(static_cast<std::size_t>(levels));
  PyramidLevel& base = levels_[static_cast<std::size_t>(first)];
  base.camera = camera;
  gray.copyTo(base.gray);
  depth.copyTo(base.depth);
  depth_fraction_ = static_cast<double>(cv::countNonZero(depth > 0.0f)) /
                    static_cast<double>(std::max<std::size_t>(1, depth.total()));
  buildCoarser(first);
}

void ImagePyramid::halveFrom(int from, int to) {
  for (int i = from; i <= to; ++i) {
    PyramidLevel& fine = levels_[static_cast<std::size_t>(i - 1)];
    PyramidLevel& coarse = levels_[static_cast<std::size_t>(i)];
    coarse.camera = fine.camera.halved();
    halveImages(fine.gray, fine.depth, coarse.gray, coarse.depth);
  }
}

void ImagePyramid::buildCoarser(int first) {
  halveFrom(first + 1, static_cast<int>(levels_.size()) - 1);
  for (int i = first; i < levels(); ++i) computeSamples(levels_[static_cast<std::size_t>(i)]);
}

}  // namespace rgbdmap
