#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <cstdint>
#include <tsl/hopscotch_map.h>
#include <vector>

namespace rgbdmap {

// Points of one keyframe in world coordinates, ready to fuse.
struct PointBatch {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> colors;  // RGB, 0..255
  std::vector<float> weights;           // inverse measurement variance (relative)

  void clear() {
    positions.clear();
    colors.clear();
    weights.clear();
  }
  std::size_t size() const { return positions.size(); }
};

// Mixes all bits of a packed voxel key: the identity hash std::hash gives integers puts
// neighbouring voxels into neighbouring buckets, which overflows hopscotch neighbourhoods.
struct VoxelKeyHash {
  std::size_t operator()(std::uint64_t key) const {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    key *= 0xc4ceb9fe1a85ec53ULL;
    key ^= key >> 33;
    return static_cast<std::size_t>(key);
  }
};

// A sparse voxel grid in which every voxel keeps the weighted running mean of the positions and
// colours that fell into it. A hash of 64-bit voxel keys (21 bits per axis) means no extent
// limit short of ±2^20 voxels per axis (±10 km at 1 cm) and memory proportional to the occupied
// voxels; one output point per voxel by construction.
class VoxelMap {
 public:
  struct Voxel {
    Eigen::Vector3f position = Eigen::Vector3f::Zero();
    Eigen::Vector3f color = Eigen::Vector3f::Zero();
    float weight = 0.0f;
    std::uint32_t observations = 0;  // points fused into this voxel
  };

  explicit VoxelMap(double voxel_size);

  void integrate(const PointBatch& batch);

  std::size_t size() const { return voxels_.size(); }
  double voxelSize() const { return voxel_size_; }
  std::uint64_t rejectedPoints() const { return rejected_; }
  // One point per voxel observed at least min_observations times, in a deterministic order
  // (the hash map's, which depends only on the sequence of insertions).
  void extract(pcl::PointCloud<pcl::PointXYZRGB>& cloud, std::uint32_t min_observations = 1) const;
  using Storage = tsl::hopscotch_map<std::uint64_t, Voxel, VoxelKeyHash>;
  const Storage& voxels() const { return voxels_; }

  // Voxel coordinates <-> key. Exposed for tests; keyFor returns false outside the key range.
  bool keyFor(const Eigen::Vector3f& p, std::uint64_t& key) const;
  static Eigen::Vector3i unpack(std::uint64_t key);

 private:
  // One keyframe's points summed per voxel before they touch the (large, cache-cold) map: a
  // frame has several points per voxel, so the map sees one update per voxel instead of one
  // per point. The weighted mean is associative, so the result is the same.
  struct FrameSum {
    Eigen::Vector3f weighted_position = Eigen::Vector3f::Zero();
    Eigen::Vector3f weighted_color = Eigen::Vector3f::Zero();
    float weight = 0.0f;
    std::uint32_t points = 0;
  };

  double voxel_size_;
  float inv_voxel_size_;
  Storage voxels_;
  tsl::hopscotch_map<std::uint64_t, FrameSum, VoxelKeyHash> frame_sums_;
  std::uint64_t rejected_ = 0;
};

}  // namespace rgbdmap
