#include "rgbdmap/mapping/keyframe_integrator.hpp"

#include <pcl/filters/statistical_outlier_removal.h>

#include <algorithm>
#include <chrono>

#include "rgbdmap/base/steady_time.hpp"

namespace rgbdmap {
namespace {

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
      smoother_{filter.smooth_radius, filter.smooth_range, 0.75, filter.smooth_noise_sigmas, true},
      tsdf_(makeTsdf(camera, filter, map)),
      pool_(threads),
      statistical_(filter.outliers == "statistical"),
      sor_mean_k_(filter.sor_mean_k),
      sor_stddev_(filter.sor_stddev),
      projector_(camera, filter.undistort) {
  if (filter.undistort && camera.hasDistortion()) lens_.emplace(camera);
}

void KeyframeIntegrator::integrate(const Frame& frame, const Eigen::Isometry3d& pose, VoxelMap& map,
                                   RunStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  filter_.apply(frame.depth, depth_, scratch_);  // the frame stays untouched
  smoother_.apply(depth_, smoothing_);
  stats.filter_latency.record(secondsSince(start));

  const auto project_start = std::chrono::steady_clock::now();
  if (statistical_) removeStatisticalOutliers(frame);
  const cv::Mat* depth = &depth_;
  const int* color_pixel_of = nullptr;
  // Colour is read through the table where fusion needs it (near surfaces), not remapped whole.
  if (lens_) {
    lens_->resampleDepth(depth_, pinhole_depth_, &pool_);
    depth = &pinhole_depth_;
    color_pixel_of = lens_->nearestRawPixel().data();
  }
  stats.project_latency.record(secondsSince(project_start));

  const auto fuse_start = std::chrono::steady_clock::now();
  tsdf_.integrate(*depth, frame.color, pose, map, &pool_, color_pixel_of);
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
