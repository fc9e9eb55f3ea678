#include "rgbdmap/mapping/keyframe_integrator.hpp"

#include <pcl/filters/statistical_outlier_removal.h>

#include <algorithm>
#include <chrono>

namespace rgbdmap {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

DepthFilter makeFilter(const Config& c) {
  DepthFilter f;
  f.min_depth = c.min_depth;
  f.max_depth = c.max_depth;
  const bool fast = c.outlier_filter == "fast";
  f.remove_flying_pixels = fast;
  f.edge_jump = c.edge_jump;
  f.min_neighbours = fast ? c.speck_min_neighbours : 0;
  return f;
}

}  // namespace

KeyframeIntegrator::KeyframeIntegrator(const Config& config)
    : filter_(makeFilter(config)),
      // Fusion averages many views of each surface, so unsmoothable pixels are dropped.
      smoother_{config.smooth_radius, config.edge_jump, 0.75, true},
      projector_(config.camera, config.undistort),
      statistical_(config.outlier_filter == "statistical"),
      sor_mean_k_(config.sor_mean_k),
      sor_stddev_(config.sor_stddev) {
  if (config.subsample) {
    // A pixel at depth z spans z / f metres; below this depth two of them fit in half a voxel.
    const double f = std::min(config.camera.fx, config.camera.fy);
    projector_.setSubsampleBelowDepth(static_cast<float>(config.voxel_size * f / 4.0));
  }
  const std::size_t pixels = static_cast<std::size_t>(config.camera.width) * config.camera.height;
  for (PointBatch* b : {&batch_, &kept_}) {
    b->positions.reserve(pixels);
    b->colors.reserve(pixels);
    b->weights.reserve(pixels);
  }
}

void KeyframeIntegrator::integrate(const Frame& frame, VoxelMap& map, RunStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  filter_.apply(frame.depth, depth_, scratch_);  // the frame stays untouched
  smoother_.apply(depth_, inverse_, valid_, sum_, count_, low_, high_);
  stats.filter_latency.record(secondsSince(start));

  const auto project_start = std::chrono::steady_clock::now();
  batch_.clear();
  projector_.project(depth_, frame.color, frame.pose, batch_);
  if (statistical_) removeStatisticalOutliers();
  stats.project_latency.record(secondsSince(project_start));

  const auto fuse_start = std::chrono::steady_clock::now();
  map.integrate(batch_);
  stats.fuse_latency.record(secondsSince(fuse_start));
  stats.integrate_latency.record(secondsSince(start));
}

void KeyframeIntegrator::removeStatisticalOutliers() {
  // The original method's filter: PCL's k-d tree based statistical outlier removal.
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
  kept_.clear();
  for (const auto i : kept) {
    kept_.positions.push_back(batch_.positions[i]);
    kept_.colors.push_back(batch_.colors[i]);
    kept_.weights.push_back(batch_.weights[i]);
  }
  std::swap(batch_, kept_);
}

}  // namespace rgbdmap
