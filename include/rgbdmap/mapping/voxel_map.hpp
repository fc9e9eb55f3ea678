#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <tsl/hopscotch_map.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "rgbdmap/base/chunked_vector.hpp"
#include "rgbdmap/base/voxel_key_hash.hpp"
#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/mapping/block_store.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/tsdf_voxel.hpp"

namespace rgbdmap {

// A sparse truncated signed distance field: each voxel holds the weighted mean of the signed
// distances along the line of sight to the surfaces measured through it (positive in front of
// a surface, negative behind it), so repeated noisy views of a surface average into one zero
// crossing instead of scattering points in front of and behind it.
//
// Voxels live in blocks of 8x8x8 allocated only near measured surfaces (TsdfIntegrator does
// that), found through a hash of block coordinates; keys pack 21 bits per axis (±2^20 blocks).
// The map a user gets is one point per surface voxel (extract()): a voxel next to a sign change
// whose |distance| is the smaller of the pair, moved onto the zero level along the gradient.
class VoxelMap {
 public:
  using Voxel = TsdfVoxel;
  static constexpr int kBlockBits = 3;
  static constexpr int kBlockEdge = 1 << kBlockBits;  // voxels per block edge
  static constexpr int kBlockVoxels = kBlockEdge * kBlockEdge * kBlockEdge;
  static constexpr std::uint32_t kNone = UINT32_MAX;
  // Coarse cells of kCellBlocks^3 blocks (0.64 m at 1 cm voxels): where blocks on disk are looked
  // for (storedNear()), and what a keyframe's footprint lists (KeyframeFootprint).
  static constexpr int kCellBits = 3;
  static constexpr int kCellBlocks = 1 << kCellBits;
  static Eigen::Vector3i cellOf(const Eigen::Vector3i& block) {
    return block.unaryExpr([](int c) { return c >> kCellBits; });  // rounds down: -1 -> -1
  }
  static double cellSize(double voxel_size) { return voxel_size * kBlockEdge * kCellBlocks; }
  struct Block {
    Eigen::Vector3i origin = Eigen::Vector3i::Zero();  // voxel coordinates of its first voxel
    std::array<Voxel, kBlockVoxels> voxels;            // x fastest, then y, then z
    std::uint32_t surface_points = 0;  // what extract() wrote from it when last counted
    std::uint64_t touched_in = 0;      // the last integration that updated it
    bool count_due = false;            // it or a neighbour changed since it was counted
    bool in_use = true;                // false: pruned, its slot waits for a new block
    // Indices of the 6 face neighbours (-x, +x, -y, +y, -z, +z), kNone where there is none:
    // counting and extraction look at them for every block, fusion marks them after each image.
    std::array<std::uint32_t, 6> neighbours{kNone, kNone, kNone, kNone, kNone, kNone};
  };

  // Voxels seen in fewer than min_observations frames are kept (more may come) but not
  // extracted.
  explicit VoxelMap(double voxel_size, std::uint32_t min_observations = 1);

  double voxelSize() const { return voxel_size_; }
  std::uint32_t minObservations() const { return min_observations_; }
  // Blocks in memory (pruned ones and those on disk excluded).
  std::size_t blockCount() const { return blocks_.size() - free_.size(); }
  // Block indices run over [0, blockSlots()); a slot whose block was pruned is not in_use.
  std::size_t blockSlots() const { return blocks_.size(); }
  // Memory of the blocks and indices (not the bytes on disk: storedBlocks()).
  std::size_t memoryBytes() const;
  // Points extract() writes. Counting is left until asked for: after each integration it would
  // revisit the blocks updated and their neighbours, about a tenth of the fusion time. With a
  // pool the blocks are counted on all its threads.
  std::size_t pointCount(WorkerPool* pool = nullptr);

  // One coloured point per surface voxel, in a deterministic order (blocks in memory in the order
  // they were created, then those on disk).
  void extract(pcl::PointCloud<pcl::PointXYZRGB>& cloud) const;
  // The same points, packed (PackedMapCloud: half the memory).
  void extract(std::vector<PackedMapPoint>& points) const;

  // --- for the integrator ---
  // Starts an integration: blocks allocated or fetched with touchBlock() until
  // finishIntegration() form its working set.
  void beginIntegration() { ++integration_; }
  std::uint64_t integrations() const { return integration_; }
  // The block with these block coordinates, created if new, added to the working set; returns
  // its index, or UINT32_MAX outside the key range or where limitTo() allows none.
  std::uint32_t touchBlock(const Eigen::Vector3i& block_coords);
  const std::vector<std::uint32_t>& touchedBlocks() const { return touched_; }
  // Adds an existing block to the working set (one that free space seen through may update).
  void touchExisting(std::uint32_t index);
  // Block coordinates by block index, for scans over every block without touching the blocks
  // themselves; a pruned slot holds kNoBlock.
  const std::vector<Eigen::Vector3i>& blockCoordinates() const { return coordinates_; }
  static const Eigen::Vector3i kNoBlock;
  // Frees the blocks far from any surface: not updated in the last `idle` integrations, and every
  // observed voxel at least `clearance` in front of a surface, or every one at least `clearance`
  // behind one. What they held is free space, or the far side of a surface that a noisy or
  // distant view's band reached (no zero crossing is in or next to them); a later view that
  // measures near them allocates them again. Returns how many were freed.
  std::size_t pruneAwayFromSurfaces(std::uint64_t idle, float clearance);
  // New blocks only where `allowed(block coordinates)` holds: a pass that fuses one region again
  // (Mapper) keeps no more than the region and what borders it.
  void limitTo(std::function<bool(const Eigen::Vector3i&)> allowed) {
    allowed_ = std::move(allowed);
  }
  // Takes `from`'s blocks (a map of the same voxel size) where `in(block coordinates)` holds, in
  // place of this map's there, which go where `from` has none: the end of a pass that fused one
  // region again (Mapper).
  void replaceRegion(const VoxelMap& from, const std::function<bool(const Eigen::Vector3i&)>& in);
  // Empty again (as a new map), keeping the blocks' memory for the blocks fused next: a re-fusion
  // pass (Mapper) starts from an empty map and grows back to about the size it had.
  void clear();
  // Hands back the memory of blocks no longer needed after clear() (a map that grew back smaller).
  void releaseUnused() { blocks_.releaseUnused(); }

  // --- blocks out of memory ---
  // Once more than `max_blocks` blocks are in memory, moves the least recently updated ones to
  // disk (BlockStore) until a quarter of that is free again; blocks updated in the last
  // `min_idle` integrations stay. A block on disk is still part of the map: extract(),
  // pointCount() and meshes read it back, and it returns to memory when an integration reaches it
  // or a block next to it (so that no block changes while a neighbour its surface depends on is
  // on disk). Returns how many blocks went; none once the disk refused one (reported once).
  std::size_t keepWithin(std::size_t max_blocks, std::uint64_t min_idle);
  const BlockStore& storedBlocks() const { return stored_; }
  // The coordinates of the blocks on disk within `radius` of `centre` (m), and some a little
  // farther: they are found by the cells of 8x8x8 blocks they lie in. A view that sees through
  // one (TsdfIntegrator) brings it back, as it updates those in memory.
  std::vector<Eigen::Vector3i> storedNear(const Eigen::Vector3f& centre, float radius) const;
  // Blocks read back from disk, for a while: each reader (a thread, an extraction) has its own.
  // What find() gave stays valid until trim().
  class BlockCache {
   public:
    void trim() {
      if (blocks_.size() > kKeepBlocks) blocks_.clear();
    }

   private:
    friend class VoxelMap;
    static constexpr std::size_t kKeepBlocks = 1024;  // 4 MB
    tsl::hopscotch_map<std::uint64_t, std::unique_ptr<Block>, VoxelKeyHash> blocks_;
    std::vector<std::uint8_t> scratch_;
  };
  // The block with these block coordinates, in memory or read back into `cache`; nullptr where
  // the map has none.
  const Block* findBlock(const Eigen::Vector3i& block_coords, BlockCache& cache) const;
  // The coordinates of every block, in memory (in index order) then on disk.
  std::vector<Eigen::Vector3i> allBlockCoordinates() const;
  Block& block(std::uint32_t index) { return blocks_[index]; }
  const Block& block(std::uint32_t index) const { return blocks_[index]; }
  // Marks the working set and the blocks next to it (whose border voxels may have changed
  // status) for counting, then clears the working set.
  void finishIntegration();

  // Voxel coordinates <-> key of the voxel that contains p. Exposed for tests; keyFor returns
  // false outside the key range.
  bool keyFor(const Eigen::Vector3f& p, std::uint64_t& key) const;
  static Eigen::Vector3i unpack(std::uint64_t key);
  // Integer coordinates (of a voxel, a block, or coarser cells) <-> a key: 21 bits an axis;
  // false outside +-2^20.
  static bool pack(const Eigen::Vector3i& coords, std::uint64_t& key);

 private:
  // A slot for a new block with this key, linked with its neighbours.
  std::uint32_t place(std::uint64_t key, const Eigen::Vector3i& block_coords);
  // Frees a block's slot for a new one: the block leaves the map (release) or goes to disk.
  void unplace(std::uint32_t index);
  void release(std::uint32_t index);
  // Writes a block to disk and frees its slot; false when the disk refuses.
  bool store(std::uint32_t index, BlockCache& cache);
  // Back from disk into a slot (touchBlock); returns its index.
  std::uint32_t restore(std::uint64_t key, const Eigen::Vector3i& block_coords);
  // A stored block, read into `cache`; nullptr where none is stored.
  const Block* readStored(std::uint64_t key, const Eigen::Vector3i& block_coords,
                          BlockCache& cache) const;
  // Counts a block's surface points and updates the total.
  void recount(Block& block, BlockCache* cache);
  // Lists a block in memory for counting.
  void markDue(std::uint32_t index);
  // Counts again the blocks next to those that left the map (in memory: at the next count).
  void recountAround(const std::vector<Eigen::Vector3i>& gone);
  // The 6 face neighbours of a block (-x, +x, -y, +y, -z, +z), nullptr where none. Without a
  // cache, those in memory only (the map has no blocks on disk).
  using Neighbours = std::array<const Block*, 6>;
  Neighbours neighboursOf(const Block& block, BlockCache* cache) const;
  // Links a new block with the blocks next to it, both ways.
  void link(std::uint32_t index, const Eigen::Vector3i& block_coords);
  // Calls emit(position, voxel) for each surface voxel of the block, in voxel order.
  template <typename Emit>
  void forEachSurfaceVoxel(const Block& block, const Neighbours& neighbours, Emit&& emit) const;
  // Calls emit(position, voxel) for every point extract() writes, in its order.
  template <typename Emit>
  void forEachPoint(Emit&& emit) const;
  // Room for the points of the last count and some: the map may have grown since, and a vector
  // that outgrows its reserve holds old and new arrays at once (a map's worth of points 1.5 times
  // over).
  std::size_t pointsToReserve() const { return points_ + points_ / 16 + kBlockVoxels; }

  double voxel_size_;
  std::uint32_t min_observations_;
  std::size_t points_ = 0;
  std::uint64_t integration_ = 0;
  tsl::hopscotch_map<std::uint64_t, std::uint32_t, VoxelKeyHash> block_index_;  // -> blocks_
  // 256 blocks (1 MB) a chunk: growing never copies the blocks there are, and a freed map goes
  // back to the system whole.
  ChunkedVector<Block, 256> blocks_;
  std::vector<Eigen::Vector3i> coordinates_;  // block coordinates by index (kNoBlock: free)
  std::vector<std::uint32_t> free_;           // pruned slots, reused first
  std::vector<std::uint32_t> touched_;
  std::vector<std::uint32_t> count_due_;                 // blocks with count_due set
  std::function<bool(const Eigen::Vector3i&)> allowed_;  // limitTo()
  BlockStore stored_;                                    // blocks out of memory (keepWithin)
  // Their keys by the cell of 8x8x8 blocks they lie in (storedNear()).
  tsl::hopscotch_map<std::uint64_t, std::vector<std::uint64_t>, VoxelKeyHash> stored_cells_;
  void noteStored(std::uint64_t key, bool stored);
  bool store_refused_ = false;
};

}  // namespace rgbdmap
