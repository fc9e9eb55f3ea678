#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "rgbdmap/base/frame.hpp"
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
struct TsdfIntegrator {
  CameraIntrinsics camera;         // pinhole (the images are undistorted before)
  double truncation = 0.03;        // m: narrowest band
  double truncation_sigmas = 3.0;  // band in units of the depth noise
  int allocation_stride = 2;       // every n-th pixel of every n-th row allocates blocks

  // depth: CV_32FC1 metres (0 = none), colour: CV_8UC3 BGR of the same size, pose camera-to-world.
  void integrate(const cv::Mat& depth, const cv::Mat& color_bgr, const Eigen::Isometry3d& pose,
                 VoxelMap& map) const;

  float bandAt(float depth) const;
};

}  // namespace rgbdmap
