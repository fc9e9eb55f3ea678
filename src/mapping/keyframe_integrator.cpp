#include "rgbdmap/mapping/keyframe_integrator.hpp"

#include <pcl/filters/statistical_outlier_removal.h>

#include <algorithm>
#include <chrono>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace rgbdmap {
namespace {

constexpr std::size_t kUndistortPixelsPerTask = 640 * 60;  // pixels per task: rows of VGA

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TsdfIntegrator makeTsdf(const CameraIntrinsics& camera, const FilterOptions& filter,
                        const MapOptions& map) {
  TsdfIntegrator t;
  t.camera = camera;
  t.truncation = map.truncation;
  t.truncation_sigmas = map.truncation_sigmas;
  t.min_incidence_cosine = map.min_incidence_cosine;
  // Samples at most half a block apart at the farthest depth fused find every block a surface
  // crosses (1 cm voxels, 4 m: every 4th pixel).
  const double block = map.voxel_size * VoxelMap::kBlockEdge;
  const int spaced = static_cast<int>(0.5 * block * camera.fx / std::max(filter.max_depth, 0.1));
  t.allocation_stride = filter.subsample ? std::clamp(spaced, 1, 4) : 1;
  return t;
}

}  // namespace

KeyframeIntegrator::KeyframeIntegrator(const CameraIntrinsics& camera, const FilterOptions& filter,
                                       const MapOptions& map, int threads)
    : filter_(filter),
      // Fusion averages many views of each surface, so unsmoothable pixels are dropped.
      smoother_{filter.smooth_radius, filter.edge_jump, 0.75, true},
      tsdf_(makeTsdf(camera, filter, map)),
      pool_(threads),
      statistical_(filter.outliers == "statistical"),
      sor_mean_k_(filter.sor_mean_k),
      sor_stddev_(filter.sor_stddev),
      undistort_(filter.undistort && camera.hasDistortion()),
      projector_(camera, filter.undistort) {
  if (undistort_) {
    // One table for depth and colour: the nearest distorted pixel of each pinhole pixel.
    const cv::Size size(camera.width, camera.height);
    cv::Mat x, y;
    cv::initUndistortRectifyMap(camera.cameraMatrix(), camera.distortion(), cv::Matx33d::eye(),
                                camera.cameraMatrix(), size, CV_32FC1, x, y);
    distorted_pixel_of_.resize(static_cast<std::size_t>(size.area()));
    for (int v = 0; v < size.height; ++v) {
      for (int u = 0; u < size.width; ++u) {
        const int su = cvRound(x.at<float>(v, u)), sv = cvRound(y.at<float>(v, u));
        const bool inside = su >= 0 && sv >= 0 && su < size.width && sv < size.height;
        distorted_pixel_of_[static_cast<std::size_t>(v) * size.width + u] =
            inside ? sv * size.width + su : -1;
      }
    }
  }
}

// Depth through the table, nearest neighbour (interpolating across an edge would invent
// surfaces), in bands of rows on the pool.
void KeyframeIntegrator::undistortDepth() {
  pinhole_depth_.create(depth_.size(), CV_32FC1);
  const float* in = depth_.ptr<float>();
  float* out = pinhole_depth_.ptr<float>();
  const std::size_t pixels = depth_.total();
  const std::size_t tasks = (pixels + kUndistortPixelsPerTask - 1) / kUndistortPixelsPerTask;
  runTasks(&pool_, tasks, [&](std::size_t task) {
    const std::size_t last = std::min(pixels, (task + 1) * kUndistortPixelsPerTask);
    for (std::size_t i = task * kUndistortPixelsPerTask; i < last; ++i) {
      const int from = distorted_pixel_of_[i];
      out[i] = from >= 0 ? in[from] : 0.0f;
    }
  });
}

void KeyframeIntegrator::integrate(const Frame& frame, VoxelMap& map, RunStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  filter_.apply(frame.depth, depth_, scratch_);  // the frame stays untouched
  smoother_.apply(depth_, smoothing_);
  stats.filter_latency.record(secondsSince(start));

  const auto project_start = std::chrono::steady_clock::now();
  if (statistical_) removeStatisticalOutliers(frame);
  const cv::Mat* depth = &depth_;
  const int* color_pixel_of = nullptr;
  // Colour is read through the table where fusion needs it (near surfaces), not remapped whole.
  if (undistort_) {
    undistortDepth();
    depth = &pinhole_depth_;
    color_pixel_of = distorted_pixel_of_.data();
  }
  stats.project_latency.record(secondsSince(project_start));

  const auto fuse_start = std::chrono::steady_clock::now();
  tsdf_.integrate(*depth, frame.color, frame.pose, map, &pool_, color_pixel_of);
  stats.fuse_latency.record(secondsSince(fuse_start));
  stats.integrate_latency.record(secondsSince(start));
}

void KeyframeIntegrator::removeStatisticalOutliers(const Frame& frame) {
  // The original method's filter: PCL's k-d tree based statistical outlier removal on the
  // back-projected points; the pixels of the points it removes lose their depth.
  batch_.clear();
  projector_.project(depth_, frame.color, frame.pose, batch_);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->resize(batch_.size());
  for (std::size_t i = 0; i < batch_.size(); ++i)
    (*cloud)[i].getVector3fMap() = batch_.positions[i];
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
  sor.setInputCloud(cloud);
  sor.setMeanK(sor_mean_k_);
  sor.setStddevMulThresh(sor_stddev_);
  pcl::Indices kept;
  sor.filter(kept);
  std::vector<char> keep(batch_.size(), 0);
  for (const auto i : kept) keep[static_cast<std::size_t>(i)] = 1;
  float* pixels = depth_.ptr<float>();
  for (std::size_t i = 0; i < batch_.size(); ++i)
    if (!keep[i]) pixels[batch_.pixels[i]] = 0.0f;
}

}  // namespace rgbdmap
