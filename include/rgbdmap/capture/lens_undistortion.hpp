#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/worker_pool.hpp"

namespace rgbdmap {

// Undoes a camera's lens distortion (Brown-Conrady, as TUM and OpenCV model it), the one way
// tracking, fusion and relocalisation share. Images are resampled to an ideal pinhole view
// through maps computed once, when the object is made (one per camera and target resolution);
// rays through raw pixel positions come from the same model.
class LensUndistortion {
 public:
  // A pinhole view of size `size` with camera matrix `pinhole` of the camera `lens`: the
  // camera's own matrix and size at full resolution, or a pyramid level's. The view is read from
  // the raw images halved `raw_level` times (2x2 means): a pyramid level resampled from raw
  // images of its own resolution, each of its pixels the mean of the raw pixels it covers,
  // instead of one bilinear sample of the full-resolution image (which aliases).
  LensUndistortion(const CameraIntrinsics& lens, const cv::Matx33d& pinhole, cv::Size size,
                   int raw_level = 0);
  // Full resolution, with the camera's own matrix.
  explicit LensUndistortion(const CameraIntrinsics& lens);

  cv::Size size() const { return size_; }

  // Grey or colour: bilinear, edge pixels repeated.
  void resampleImage(const cv::Mat& raw, cv::Mat& pinhole) const;
  // Depth (CV_32FC1): the nearest raw sample, since interpolating across a depth edge would
  // invent a surface; 0 where the pinhole pixel lies outside the raw image. On `pool`'s threads
  // in bands of rows, when given.
  void resampleDepth(const cv::Mat& raw, cv::Mat& pinhole, WorkerPool* pool = nullptr) const;
  // The nearest samples resampleDepth takes, as a table: for each pinhole pixel (row-major) the
  // index of the raw pixel that saw it, or -1. For reading colour only where it is needed.
  const std::vector<int>& nearestRawPixel() const { return nearest_raw_pixel_; }

  // Normalised coordinates (x/z, y/z) of the rays through raw pixel positions (subpixel).
  static void rays(const CameraIntrinsics& lens, const std::vector<cv::Point2f>& pixels,
                   std::vector<cv::Point2f>& rays);
  // The other way: a ray's normalised coordinates (x/z, y/z) as the lens bends them, before the
  // camera matrix (what OpenCV's projectPoints does per point).
  static void distortRay(const CameraIntrinsics& lens, float& x, float& y);

 private:
  cv::Size raw_size_, size_;
  cv::Mat map_x_, map_y_;               // CV_32FC1: the raw position each pinhole pixel sees
  std::vector<int> nearest_raw_pixel_;  // those positions rounded, -1 outside the raw image
};

}  // namespace rgbdmap
