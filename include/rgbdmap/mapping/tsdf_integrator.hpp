#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/mapping/back_projector.hpp"
#include "rgbdmap/mapping/map_options.hpp"
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
  CameraIntrinsics camera;  // pinhole (the images are undistorted before)
  // Defaults: the map.* keys'.
  double truncation = MapOptions{}.truncation;                // m: narrowest band
  double truncation_sigmas = MapOptions{}.truncation_sigmas;  // band in units of the depth noise
  int allocation_stride = 2;  // every n-th pixel of every n-th row allocates blocks
  // Incidence cosines are clamped here (1: along the ray).
  double min_incidence_cosine = MapOptions{}.min_incidence_cosine;
  // Blocks a view sees through are looked for in every n-th image only: a scan of the whole map
  // costs about as much as allocating, and what went away is carved a few frames later instead.
  int seen_through_every = 4;
  int normal_cell = 4;  // incidence is taken on cells of this many pixels squared (a power of 2)

  // depth: CV_32FC1 metres (0 = none), colour: CV_8UC3 BGR of the same size, pose camera-to-world.
  // With a pool the voxels are updated on all its threads (each block by one thread: the map
  // is the same whatever the thread count). Buffers are kept between calls.
  // color_pixel_of: for each depth pixel, the colour pixel that saw the same ray, -1 for none
  // (lens distortion undone by lookup: only voxels near a surface read colour, so remapping the
  // whole colour image would be wasted); nullptr: the same pixel.
  void integrate(const cv::Mat& depth, const cv::Mat& color_bgr, const Eigen::Isometry3d& pose,
                 VoxelMap& map, WorkerPool* pool = nullptr, const int* color_pixel_of = nullptr);

  // The band a measured depth updates (+-band around it). Computed where needed rather than
  // stored per pixel: a per-pixel table was four times the depth image and fusion waited on its
  // cache misses. (Its weight is scale / sigma^2 relative to a head-on measurement at 1 m,
  // scale being cos(incidence): computed in fuseBlock's vector code.)
  float bandAt(float depth) const {
    return std::max(static_cast<float>(truncation),
                    static_cast<float>(truncation_sigmas) * kinectDepthSigma(depth));
  }

 private:
  // What updating a block needs of one image.
  struct ImageView {
    Eigen::Isometry3f world_to_camera;
    Eigen::Vector3f dx, dy, dz;  // one voxel along the world axes, in the camera frame
    float voxel = 0.0f;
    const float* depth = nullptr;         // contiguous, metres
    const std::uint8_t* color = nullptr;  // contiguous BGR
    const int* color_pixel_of = nullptr;  // see integrate()
    int width = 0, height = 0;
  };
  void fuseBlock(const ImageView& view, VoxelMap::Block& block) const;
  void prepareIncidence(const cv::Mat& depth, WorkerPool* pool);
  // cos(incidence) of pixel (u, v), clamped at min_incidence_cosine.
  float incidenceAt(int u, int v) const {
    return cosine_[(v >> cell_bits_) * grid_width_ + (u >> cell_bits_)];
  }
  void allocate(const cv::Mat& depth, const Eigen::Isometry3d& pose, VoxelMap& map,
                WorkerPool* pool);
  void touchSeenThrough(const cv::Mat& depth, const Eigen::Isometry3f& world_to_camera,
                        VoxelMap& map, WorkerPool* pool);

  cv::Mat depth_, color_;                    // continuous copies, made only when the input is not
  std::vector<Eigen::Vector3f> cell_point_;  // incidence grid, row-major: each cell's point
  std::vector<float> cosine_;                // and its incidence
  std::vector<float> column_sums_;           // per task: depth sums and counts of a cell row
  int cell_bits_ = 2;                        // cells are 2^cell_bits_ pixels wide
  int grid_width_ = 0, grid_height_ = 0;
  std::vector<std::vector<Eigen::Vector3i>> crossed_;  // blocks each allocation task's rays cross
  std::vector<std::vector<std::uint32_t>> seen_through_;  // blocks each scan task found
};

}  // namespace rgbdmap
