#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap {

// Where a keyframe's surfaces lie in the map, coarsely: the cells of the voxel map
// (VoxelMap::cellOf, 0.64 m at 1 cm voxels) that its depth, within the fused range, falls in. A
// pass after a loop (Mapper) re-fuses only the cells the keyframes it moved saw, before and after
// the move, from the keyframes that saw them or the cells next to them (a TSDF band and a voxel's
// neighbours reach a few centimetres past a surface, never a cell).
class KeyframeFootprint {
 public:
  KeyframeFootprint() = default;
  // From every kStride-th pixel of `depth` (metres, 0: none) in [min_depth, max_depth], seen from
  // `pose`.
  KeyframeFootprint(const cv::Mat& depth, const CameraIntrinsics& camera,
                    const Eigen::Isometry3d& pose, double voxel_size, double min_depth,
                    double max_depth);

  // Whether a TSDF block (block coordinates) lies in one of `cells` (sorted).
  static bool holds(const std::vector<std::uint64_t>& cells, const Eigen::Vector3i& block);
  // Sorts cell keys and keeps each once.
  static void sortUnique(std::vector<std::uint64_t>& cells);

  // Sorted, each once.
  const std::vector<std::uint64_t>& cells() const { return cells_; }
  // The same surfaces moved by `motion` (a loop's correction of the keyframe), roughly: the cells
  // the cells' centres move to. (Surfaces near a cell's face may cross into the next cell: the
  // footprint of the moved keyframe's depth says where exactly.)
  KeyframeFootprint moved(const Eigen::Isometry3d& motion, double voxel_size) const;
  // Sorted cells and the 26 around each, sorted.
  static std::vector<std::uint64_t> dilate(const std::vector<std::uint64_t>& cells);
  std::size_t memoryBytes() const { return cells_.capacity() * sizeof(std::uint64_t); }

  static constexpr int kStride = 8;  // pixels

 private:
  static std::uint64_t key(const Eigen::Vector3i& cell);
  static Eigen::Vector3i unpack(std::uint64_t key);

  std::vector<std::uint64_t> cells_;
};

}  // namespace rgbdmap
