#pragma once

#include <tsl/hopscotch_map.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/surface_cloud.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// Merges the surface points of several submaps into one map: each point, moved by its submap's
// pose, lands in a voxel of the merged map; a voxel's point is the weighted mean of what landed
// in it (positions and colours, weighted by how much was fused behind each), so a surface two
// submaps saw becomes one layer once the submaps are aligned. Voxels come out in the order they
// were first hit, so the same input gives the same map.
class PointMerger {
 public:
  explicit PointMerger(double voxel_size) : voxel_size_(voxel_size) {}
  void add(const SurfaceCloud& points, const Eigen::Isometry3d& pose);
  void extract(MapCloud& cloud) const;
  std::size_t size() const { return sums_.size(); }

 private:
  struct Sum {  // floats: a merged map has as many of these as points
    Eigen::Vector3f position = Eigen::Vector3f::Zero();
    Eigen::Vector3f color = Eigen::Vector3f::Zero();
    float weight = 0.0f;
  };
  double voxel_size_;
  tsl::hopscotch_map<std::uint64_t, std::uint32_t, VoxelKeyHash> index_;
  std::vector<Sum> sums_;
};

}  // namespace rgbdmap
