#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// The surface points of a closed submap, kept compactly (12 bytes a point instead of 20): a
// submap lives as long as the run, and a room walked for a while is covered by many of them.
// Positions are quantised on a grid fitted to the cloud's bounding box (65535 steps per axis:
// 0.15 mm for a 10 m submap, far below the voxel size); weights to 1/16. A cloud too large for
// steps of kMaxStep (over 16 m across) is kept as it is.
class SurfaceCloud {
 public:
  SurfaceCloud() = default;
  explicit SurfaceCloud(const std::vector<VoxelMap::SurfacePoint>& points);

  static constexpr float kMaxStep = 0.00025f;  // m

  std::size_t size() const { return exact_.empty() ? points_.size() : exact_.size(); }
  std::size_t memoryBytes() const {
    return points_.capacity() * sizeof(Packed) + exact_.capacity() * sizeof(VoxelMap::SurfacePoint);
  }
  VoxelMap::SurfacePoint operator[](std::size_t i) const;

 private:
  struct Packed {
    std::uint16_t x, y, z;
    std::uint16_t weight;  // 1/16ths, saturating
    std::uint8_t r, g, b;
  };
  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  Eigen::Vector3f step_ = Eigen::Vector3f::Ones();
  std::vector<Packed> points_;
  std::vector<VoxelMap::SurfacePoint> exact_;
};

}  // namespace rgbdmap
