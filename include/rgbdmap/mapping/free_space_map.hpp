#pragma once

#include <tsl/hopscotch_map.h>

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/option_keys.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// The OctoMap written with --octomap (config section "octomap").
struct OctomapOptions {
  double resolution = 0.05;  // m, leaf edge
  // Every this many pixels of a keyframe's rows and columns a ray is cast through free space: at
  // 5 cm cells and 3 m, 10 pixels are 6 cm apart, and the next keyframes fill what one misses.
  int ray_stride = 10;
  double max_range = 4.0;  // m: farther measurements carve no free space (their noise is cm)
};

Keys octomapKeys(OctomapOptions& o);

// The space the camera saw through, at a coarse resolution: the TSDF keeps only a band around
// surfaces (and frees blocks of empty space), so a map a robot can plan in needs the rays
// themselves. Each keyframe's rays (every ray_stride pixels) mark the cells they cross before
// their measurement, at the pose the keyframe is fused at; a loop's later correction of a few
// centimetres is not carved again (a cell is 5 cm).
class FreeSpaceMap {
 public:
  explicit FreeSpaceMap(const OctomapOptions& options);

  // `depth` in metres (CV_32F, 0 = none), `pose` camera-to-world.
  void carve(const cv::Mat& depth, const CameraIntrinsics& camera, const Eigen::Isometry3d& pose);

  double resolution() const { return resolution_; }
  std::size_t freeCells() const { return free_cells_; }
  std::size_t memoryBytes() const;
  // Calls visit(cell) with the integer coordinates of each cell seen empty (cell c spans
  // [c, c + 1) * resolution on each axis).
  template <typename Visit>
  void forEachFree(Visit&& visit) const {
    for (const auto& [key, index] : index_) {
      const Eigen::Vector3i origin = unpack(key) * kBlockEdge;
      const Block& block = blocks_[index];
      for (int i = 0; i < kBlockCells; ++i)
        if (block[static_cast<std::size_t>(i)])
          visit(Eigen::Vector3i(origin.x() + (i & (kBlockEdge - 1)),
                                origin.y() + ((i >> kBlockBits) & (kBlockEdge - 1)),
                                origin.z() + (i >> (2 * kBlockBits))));
    }
  }

 private:
  static constexpr int kBlockBits = 4;
  static constexpr int kBlockEdge = 1 << kBlockBits;
  static constexpr int kBlockCells = kBlockEdge * kBlockEdge * kBlockEdge;
  using Block = std::array<std::uint8_t, kBlockCells>;  // 1 where seen empty

  void mark(const Eigen::Vector3i& cell);
  // Block coordinates <-> key: 21 bits per axis, offset to be non-negative.
  static std::uint64_t pack(const Eigen::Vector3i& block);
  static Eigen::Vector3i unpack(std::uint64_t key);

  double resolution_;
  int ray_stride_;
  double max_range_;
  std::size_t free_cells_ = 0;
  tsl::hopscotch_map<std::uint64_t, std::uint32_t, VoxelKeyHash> index_;  // block key -> blocks_
  std::vector<Block> blocks_;
  std::uint64_t last_key_ = UINT64_MAX;  // the block marked last, looked up once per run of cells
  std::uint32_t last_index_ = 0;
};

}  // namespace rgbdmap
