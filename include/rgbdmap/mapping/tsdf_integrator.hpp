#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// Fuses one depth image into a VoxelMap along the lines of sight (projective TSDF, as
// KinectFusion and Open3D): the blocks within the truncation band of each measured pixel are
// allocated, then every voxel of those blocks is projected into the image and takes the signed
// distance between the measured depth and its own depth, truncated to the band. Voxels in front
// of a surface by more than the band are updated as free space, so what noise put there fades.
//
// The band is noise-aware: max(truncation, truncation_sigmas * sigma(depth)) with the Kinect
// axial noise sigma(z), so far surfaces (sigma 2.6 cm at 4 m) are averaged over a wide enough
// band while near ones stay sharp; each measurement weighs 1 / sigma(depth)^2.
//
// Distances are taken to the surface, not along the ray. Where a line of sight grazes a surface
// (a floor seen from afar) the distance along the ray overstates the distance to the surface by
// 1 / cos(incidence): a voxel on the floor a little before the measured point would look like
// free space, every such frame would carve what closer views saw well, and the field would grow
// so steep that a crossing's voxels both lie over a voxel from it. So each pixel's distances are
// scaled by the cosine of its incidence (from the depth image's own normal, clamped at
// min_incidence_cosine), and grazing measurements weigh that much less. A surface that went away is
// carved by the views that see through it: blocks already in the map in front of a measurement
// are updated too, and free space weighs as much as a measurement at the voxel's own depth.
struct TsdfIntegrator {
  CameraIntrinsics camera;            // pinhole (the images are undistorted before)
  double truncation = 0.03;           // m: narrowest band
  double truncation_sigmas = 3.0;     // band in units of the depth noise
  int allocation_stride = 2;          // every n-th pixel of every n-th row allocates blocks
  double min_incidence_cosine = 0.2;  // incidence cosines are clamped here (1: along the ray)
  // Blocks a view sees through are looked for in every n-th image only: a scan of the whole map
  // costs about as much as allocating, and what went away is carved a few frames later instead.
  int seen_through_every = 4;
  int normal_cell = 4;  // incidence is taken on cells of this many pixels squared

  // depth: CV_32FC1 metres (0 = none), colour: CV_8UC3 BGR of the same size, pose camera-to-world.
  // With a pool the voxels are updated on all its threads (each block by one thread: the map
  // is the same whatever the thread count). Buffers are kept between calls.
  void integrate(const cv::Mat& depth, const cv::Mat& color_bgr, const Eigen::Isometry3d& pose,
                 VoxelMap& map, WorkerPool* pool = nullptr);

  // What fusion needs of one pixel, computed once per image instead of once per voxel.
  struct Sample {
    float depth = 0.0f;   // m, 0 = none
    float band = 0.0f;    // m: updates within +-band of the depth
    float scale = 1.0f;   // distance to the surface per distance along the ray: cos(incidence)
    float weight = 0.0f;  // scale / sigma^2, 1 at 1 m head-on
  };

 private:
  void prepareSamples(const cv::Mat& depth, WorkerPool* pool);
  std::vector<Sample> samples_;                                     // row-major, one per pixel
  cv::Mat valid_, valid_float_, depth_mean_, valid_mean_, cosine_;  // incidence grid
};

}  // namespace rgbdmap
