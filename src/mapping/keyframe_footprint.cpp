#include "rgbdmap/mapping/keyframe_footprint.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {
namespace {

constexpr int kBits = 21;
constexpr std::int64_t kOffset = std::int64_t{1} << (kBits - 1);
constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;

double cellSize(double voxel_size) {
  return voxel_size * VoxelMap::kBlockEdge * KeyframeFootprint::kCellBlocks;
}

}  // namespace

std::uint64_t KeyframeFootprint::key(const Eigen::Vector3i& cell) {
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis)
    key |= (static_cast<std::uint64_t>(cell[axis] + kOffset) & kMask) << (kBits * axis);
  return key;
}

Eigen::Vector3i KeyframeFootprint::unpack(std::uint64_t key) {
  Eigen::Vector3i cell;
  for (int axis = 0; axis < 3; ++axis)
    cell[axis] =
        static_cast<int>(static_cast<std::int64_t>((key >> (kBits * axis)) & kMask) - kOffset);
  return cell;
}

KeyframeFootprint::KeyframeFootprint(const cv::Mat& depth, const CameraIntrinsics& camera,
                                     const Eigen::Isometry3d& pose, double voxel_size,
                                     double min_depth, double max_depth) {
  const double cell = cellSize(voxel_size);
  const Eigen::Matrix3d rotation = pose.linear();
  for (int v = kStride / 2; v < depth.rows; v += kStride) {
    const float* row = depth.ptr<float>(v);
    for (int u = kStride / 2; u < depth.cols; u += kStride) {
      const double z = row[u];
      if (!(z >= min_depth && z <= max_depth)) continue;
      const Eigen::Vector3d p = rotation * Eigen::Vector3d((u - camera.cx) * z / camera.fx,
                                                           (v - camera.cy) * z / camera.fy, z) +
                                pose.translation();
      const Eigen::Vector3d c = (p / cell).array().floor();
      if (!(c.array().abs() < static_cast<double>(kOffset - 1)).all()) continue;
      cells_.push_back(key(c.cast<int>()));
    }
  }
  sortUnique();
}

void KeyframeFootprint::sortUnique() {
  std::sort(cells_.begin(), cells_.end());
  cells_.erase(std::unique(cells_.begin(), cells_.end()), cells_.end());
  cells_.shrink_to_fit();
}

KeyframeFootprint KeyframeFootprint::moved(const Eigen::Isometry3d& motion,
                                           double voxel_size) const {
  const double cell = cellSize(voxel_size);
  KeyframeFootprint out;
  out.cells_.reserve(cells_.size());
  for (const std::uint64_t k : cells_) {
    const Eigen::Vector3d centre = (unpack(k).cast<double>().array() + 0.5).matrix() * cell;
    const Eigen::Vector3d c = ((motion * centre) / cell).array().floor();
    if (!(c.array().abs() < static_cast<double>(kOffset - 1)).all()) continue;
    out.cells_.push_back(key(c.cast<int>()));
  }
  out.sortUnique();
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
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace rgbdmap
