#include "rgbdmap/mapping/free_space_map.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdmap {
namespace {

constexpr int kKeyBits = 21;
constexpr std::int64_t kKeyOffset = std::int64_t{1} << (kKeyBits - 1);
constexpr std::uint64_t kKeyMask = (std::uint64_t{1} << kKeyBits) - 1;

}  // namespace

Keys octomapKeys(OctomapOptions& o) {
  return {
      number("octomap.resolution", &o.resolution, 0.01, 10, "OctoMap leaf edge (m)"),
      integer("octomap.ray_stride", &o.ray_stride, 1, 640,
              "a free-space ray is cast every this many pixels of a keyframe's rows and columns"),
      number("octomap.max_range", &o.max_range, 0.1, 100,
             "measurements farther than this carve no free space (m)"),
  };
}

FreeSpaceMap::FreeSpaceMap(const OctomapOptions& options)
    : resolution_(options.resolution),
      ray_stride_(std::max(1, options.ray_stride)),
      max_range_(options.max_range) {}

std::uint64_t FreeSpaceMap::pack(const Eigen::Vector3i& block) {
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis)
    key |= (static_cast<std::uint64_t>(block[axis] + kKeyOffset) & kKeyMask) << (kKeyBits * axis);
  return key;
}

Eigen::Vector3i FreeSpaceMap::unpack(std::uint64_t key) {
  Eigen::Vector3i block;
  for (int axis = 0; axis < 3; ++axis)
    block[axis] = static_cast<int>(
        static_cast<std::int64_t>((key >> (kKeyBits * axis)) & kKeyMask) - kKeyOffset);
  return block;
}

std::size_t FreeSpaceMap::memoryBytes() const {
  return blocks_.capacity() * sizeof(Block) +
         index_.bucket_count() * (sizeof(std::uint64_t) + sizeof(std::uint32_t) + 8);
}

void FreeSpaceMap::mark(const Eigen::Vector3i& cell) {
  const Eigen::Vector3i block(cell.x() >> kBlockBits, cell.y() >> kBlockBits,
                              cell.z() >> kBlockBits);
  const std::uint64_t key = pack(block);
  if (key != last_key_) {
    const auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(blocks_.size()));
    if (inserted) blocks_.emplace_back().fill(0);
    last_key_ = key;
    last_index_ = it->second;
  }
  const int i = (cell.x() & (kBlockEdge - 1)) | ((cell.y() & (kBlockEdge - 1)) << kBlockBits) |
                ((cell.z() & (kBlockEdge - 1)) << (2 * kBlockBits));
  std::uint8_t& c = blocks_[last_index_][static_cast<std::size_t>(i)];
  free_cells_ += c == 0 ? 1 : 0;
  c = 1;
}

void FreeSpaceMap::carve(const cv::Mat& depth, const CameraIntrinsics& camera,
                         const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d origin = pose.translation() / resolution_;  // in cells
  const Eigen::Vector3i start = origin.array().floor().cast<int>();
  for (int v = ray_stride_ / 2; v < depth.rows; v += ray_stride_) {
    const float* row = depth.ptr<float>(v);
    for (int u = ray_stride_ / 2; u < depth.cols; u += ray_stride_) {
      const double z = row[u];
      if (!(z > 0.0) || z > max_range_) continue;
      const Eigen::Vector3d ray_camera((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy,
                                       1.0);
      const double length = z * ray_camera.norm() / resolution_;  // in cells
      // Up to one cell short of the measurement: the cell it lies in is surface, not free space.
      const double free_length = length - 1.0;
      if (free_length <= 0.0) continue;
      const Eigen::Vector3d direction = (pose.linear() * ray_camera).normalized();
      // Amanatides and Woo's traversal: step into whichever neighbouring cell the ray reaches
      // first.
      Eigen::Vector3i cell = start;
      Eigen::Vector3i step;
      Eigen::Vector3d next, delta;
      for (int a = 0; a < 3; ++a) {
        const double d = direction[a];
        step[a] = d > 0 ? 1 : -1;
        delta[a] = d != 0.0 ? std::abs(1.0 / d) : INFINITY;
        const double boundary = d > 0 ? std::floor(origin[a]) + 1.0 : std::floor(origin[a]);
        next[a] = d != 0.0 ? (boundary - origin[a]) / d : INFINITY;
      }
      double travelled = 0.0;
      while (travelled < free_length) {
        mark(cell);
        int a = 0;
        if (next[1] < next[a]) a = 1;
        if (next[2] < next[a]) a = 2;
        travelled = next[a];
        next[a] += delta[a];
        cell[a] += step[a];
      }
    }
  }
}

}  // namespace rgbdmap
