#include "rgbdmap/mapping/keyframe_footprint.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {
namespace {

// The key of the cell a point lies in (in cell units); false far beyond any map (or NaN), and
// within a cell of the key range's edge, so that the cells next to it have keys too.
bool cellIn(const Eigen::Vector3d& p, std::uint64_t& key) {
  constexpr double kLimit = (1 << 20) - 2;
  if (!(p.array().abs() < kLimit).all()) return false;
  return VoxelMap::pack(p.array().floor().cast<int>().matrix(), key);
}

}  // namespace

std::uint64_t KeyframeFootprint::key(const Eigen::Vector3i& cell) {
  std::uint64_t key = 0;
  VoxelMap::pack(cell, key);  // cells are within range (cellIn())
  return key;
}

Eigen::Vector3i KeyframeFootprint::unpack(std::uint64_t key) { return VoxelMap::unpack(key); }

bool KeyframeFootprint::holds(const std::vector<std::uint64_t>& cells,
                              const Eigen::Vector3i& block) {
  return std::binary_search(cells.begin(), cells.end(), key(VoxelMap::cellOf(block)));
}

void KeyframeFootprint::sortUnique(std::vector<std::uint64_t>& cells) {
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
}

KeyframeFootprint::KeyframeFootprint(const cv::Mat& depth, const CameraIntrinsics& camera,
                                     const Eigen::Isometry3d& pose, double voxel_size,
                                     double min_depth, double max_depth) {
  const double cell = VoxelMap::cellSize(voxel_size);
  const Eigen::Matrix3d rotation = pose.linear();
  for (int v = kStride / 2; v < depth.rows; v += kStride) {
    const float* row = depth.ptr<float>(v);
    for (int u = kStride / 2; u < depth.cols; u += kStride) {
      const double z = row[u];
      if (!(z >= min_depth && z <= max_depth)) continue;
      const Eigen::Vector3d p = rotation * Eigen::Vector3d((u - camera.cx) * z / camera.fx,
                                                           (v - camera.cy) * z / camera.fy, z) +
                                pose.translation();
      std::uint64_t k;
      if (cellIn(p / cell, k)) cells_.push_back(k);
    }
  }
  sortUnique(cells_);
  cells_.shrink_to_fit();
}

KeyframeFootprint KeyframeFootprint::moved(const Eigen::Isometry3d& motion,
                                           double voxel_size) const {
  const double cell = VoxelMap::cellSize(voxel_size);
  KeyframeFootprint out;
  out.cells_.reserve(cells_.size());
  for (const std::uint64_t from : cells_) {
    const Eigen::Vector3d centre = (unpack(from).cast<double>().array() + 0.5).matrix() * cell;
    std::uint64_t to;
    if (cellIn((motion * centre) / cell, to)) out.cells_.push_back(to);
  }
  sortUnique(out.cells_);
  return out;
}

std::vector<std::uint64_t> KeyframeFootprint::dilate(const std::vector<std::uint64_t>& cells) {
  std::vector<std::uint64_t> out;
  out.reserve(cells.size() * 27);
  for (const std::uint64_t k : cells) {
    const Eigen::Vector3i c = unpack(k);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) out.push_back(key(c + Eigen::Vector3i(dx, dy, dz)));
  }
  sortUnique(out);
  return out;
}

}  // namespace rgbdmap
