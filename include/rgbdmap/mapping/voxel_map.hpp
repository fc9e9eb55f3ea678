#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <tsl/hopscotch_map.h>

#include <Eigen/Core>
#include <array>
#include <cstdint>
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

// Mixes all bits of a packed key: the identity hash std::hash gives integers puts neighbouring
// blocks into neighbouring buckets, which overflows hopscotch neighbourhoods.
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
// colours that fell into it. Voxel keys pack 21 bits per axis: no extent limit short of ±2^20
// voxels per axis (±10 km at 1 cm), memory proportional to the occupied space, one output point
// per voxel by construction.
//
// Layout (for speed): a keyframe touches ~100k voxels, and one random hash lookup per voxel in
// a table of millions is one cache miss each, most of a keyframe's cost. So voxels are grouped
// in blocks of 4x4x4: the hash holds blocks, a block holds the indices of its voxels (256 B), and
// the voxels themselves sit in one array in the order they were created. Consecutive pixels
// mostly stay in one block (one hash lookup per block, not per point), and a revisit reads
// voxels in about the order it created them. (8^3 blocks fuse ~8% faster, but cost 2 KB per
// isolated voxel: 0.7 GB for the 360k scattered points of a test.)
class VoxelMap {
 public:
  struct Voxel {
    Eigen::Vector3f position = Eigen::Vector3f::Zero();
    Eigen::Vector3f color = Eigen::Vector3f::Zero();
    float weight = 0.0f;
    std::uint32_t observations = 0;  // points fused into this voxel
  };

  // Voxels that received fewer than min_observations points are kept (more may come) but not
  // extracted: with many frames, a voxel holding a single point is almost always a noise tail.
  explicit VoxelMap(double voxel_size, std::uint32_t min_observations = 1);

  void integrate(const PointBatch& batch);

  std::size_t size() const { return voxels_.size(); }  // every voxel
  std::size_t pointCount() const { return points_; }   // voxels extract() writes
  std::uint32_t minObservations() const { return min_observations_; }
  double voxelSize() const { return voxel_size_; }
  std::uint64_t rejectedPoints() const { return rejected_; }
  // One point per voxel observed at least min_observations times (the map's own by default), in
  // a deterministic order (the order the voxels were created in).
  void extract(pcl::PointCloud<pcl::PointXYZRGB>& cloud) const {
    extract(cloud, min_observations_);
  }
  void extract(pcl::PointCloud<pcl::PointXYZRGB>& cloud, std::uint32_t min_observations) const;
  // Every voxel, in the order they were created.
  const std::vector<Voxel>& voxels() const { return voxels_; }

  // Voxel coordinates <-> key. Exposed for tests; keyFor returns false outside the key range.
  bool keyFor(const Eigen::Vector3f& p, std::uint64_t& key) const;
  static Eigen::Vector3i unpack(std::uint64_t key);

 private:
  static constexpr int kBlockBits = 2;  // 4 voxels per block edge
  static constexpr int kBlockVoxels = 1 << (3 * kBlockBits);
  // Index + 1 in voxels_ of each voxel of a block; 0 = not observed yet.
  using Block = std::array<std::uint32_t, kBlockVoxels>;

  // Where the slot of the voxel containing p is (block index * kBlockVoxels + position in the
  // block), creating the block if new; false outside the key range.
  bool slotOf(const Eigen::Vector3f& p, std::uint32_t& slot);

  double voxel_size_;
  double inv_voxel_size_;
  std::uint32_t min_observations_;
  std::size_t points_ = 0;  // voxels with at least min_observations_ points
  tsl::hopscotch_map<std::uint64_t, std::uint32_t, VoxelKeyHash> block_index_;  // key -> blocks_
  std::vector<Block> blocks_;
  std::vector<Voxel> voxels_;
  std::vector<std::uint32_t> point_slots_, point_voxels_;  // per point of a batch (scratch)
  // The block of the previous lookup: neighbouring pixels usually fall into the same one.
  std::uint64_t last_block_key_ = 0;
  std::uint32_t last_block_ = UINT32_MAX;
  std::uint64_t rejected_ = 0;
};

}  // namespace rgbdmap
