#include "rgbdmap/capture/lens_undistortion.hpp"

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace rgbdmap {
namespace {

constexpr std::size_t kPixelsPerTask = 640 * 60;  // depth resampled per task: rows of VGA

}  // namespace

LensUndistortion::LensUndistortion(const CameraIntrinsics& lens, const cv::Matx33d& pinhole,
                                   cv::Size size, int raw_level)
    : raw_size_(lens.width >> raw_level, lens.height >> raw_level), size_(size) {
  cv::initUndistortRectifyMap(lens.cameraMatrix(), lens.distortion(), cv::noArray(), pinhole, size,
                              CV_32FC1, map_x_, map_y_);
  if (raw_level > 0) {
    // Pixel centres on the halved raw grid: x' = (x + 0.5) / 2^k - 0.5.
    const double s = 1.0 / static_cast<double>(1 << raw_level);
    map_x_.convertTo(map_x_, CV_32FC1, s, 0.5 * s - 0.5);
    map_y_.convertTo(map_y_, CV_32FC1, s, 0.5 * s - 0.5);
  }
  // Rounded as cv::remap rounds for its nearest-neighbour lookup, against the raw image.
  nearest_raw_pixel_.resize(static_cast<std::size_t>(size.area()));
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) {
      const int su = cvRound(map_x_.at<float>(v, u)), sv = cvRound(map_y_.at<float>(v, u));
      const bool inside = su >= 0 && sv >= 0 && su < raw_size_.width && sv < raw_size_.height;
      nearest_raw_pixel_[static_cast<std::size_t>(v) * size.width + u] =
          inside ? sv * raw_size_.width + su : -1;
    }
  }
}

LensUndistortion::LensUndistortion(const CameraIntrinsics& lens)
    : LensUndistortion(lens, lens.cameraMatrix(), cv::Size(lens.width, lens.height)) {}

void LensUndistortion::resampleImage(const cv::Mat& raw, cv::Mat& pinhole) const {
  cv::remap(raw, pinhole, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
}

void LensUndistortion::resampleDepth(const cv::Mat& raw, cv::Mat& pinhole, WorkerPool* pool) const {
  CV_Assert(raw.type() == CV_32FC1 && raw.isContinuous() && raw.size() == raw_size_);
  pinhole.create(size_, CV_32FC1);
  const float* in = raw.ptr<float>();
  float* out = pinhole.ptr<float>();
  const std::size_t pixels = nearest_raw_pixel_.size();
  const std::size_t tasks = (pixels + kPixelsPerTask - 1) / kPixelsPerTask;
  runTasks(pool, tasks, [&](std::size_t task) {
    const std::size_t last = std::min(pixels, (task + 1) * kPixelsPerTask);
    for (std::size_t i = task * kPixelsPerTask; i < last; ++i) {
      const int from = nearest_raw_pixel_[i];
      out[i] = from >= 0 ? in[from] : 0.0f;
    }
  });
}

void LensUndistortion::rays(const CameraIntrinsics& lens, const std::vector<cv::Point2f>& pixels,
                            std::vector<cv::Point2f>& rays) {
  cv::undistortPoints(pixels, rays, lens.cameraMatrix(), lens.distortion());
}

void LensUndistortion::distortRay(const CameraIntrinsics& lens, float& x, float& y) {
  const float r2 = x * x + y * y;
  const float radial =
      1.0f + r2 * (static_cast<float>(lens.k1) +
                   r2 * (static_cast<float>(lens.k2) + r2 * static_cast<float>(lens.k3)));
  const float p1 = static_cast<float>(lens.p1), p2 = static_cast<float>(lens.p2);
  const float xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  const float yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
  x = xd;
  y = yd;
}

}  // namespace rgbdmap
