#pragma once

#include <tsl/hopscotch_map.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rgbdmap/base/voxel_key_hash.hpp"
#include "rgbdmap/mapping/spill_file.hpp"
#include "rgbdmap/mapping/tsdf_voxel.hpp"

namespace rgbdmap {

// The blocks of a voxel map that left memory (VoxelMap::keepWithin): on disk in a scratch file
// (SpillFile), indexed in memory by block key with the points the map writes from each. A block
// is written as which of its voxels were ever observed (a 512-bit mask) and those voxels only:
// the band around a surface leaves most of a block's 4 KB unobserved.
//
// A block taken back leaves its bytes in the file; when those are most of it, the file is written
// again with the stored blocks only (a camera walking to and fro between two ends of a floor
// would otherwise grow it without end).
class BlockStore {
 public:
  static constexpr int kVoxels = 512;
  using Voxels = std::array<TsdfVoxel, kVoxels>;
  struct Stored {
    std::uint64_t offset = 0;
    std::uint64_t touched_in = 0;  // the last integration that updated the block (VoxelMap)
    std::uint32_t bytes = 0;
    std::uint32_t surface_points = 0;  // what the map writes from the block
    // The least and greatest distance its observed voxels hold, in TsdfVoxel steps (none
    // observed: least > greatest), for freeing blocks away from surfaces without reading them.
    std::int16_t least_sdf = 0, greatest_sdf = 0;
  };
  using Index = tsl::hopscotch_map<std::uint64_t, Stored, VoxelKeyHash>;

  // The file is written again once the bytes taken back exceed `compact_above` plus twice those
  // stored: it stays within `compact_above` and 3x the stored bytes, and rewrites are far apart.
  explicit BlockStore(std::uint64_t compact_above = 64ull << 20) : compact_above_(compact_above) {}

  // Writes a block; false, with `error` naming the folder and what went wrong, when the disk
  // refuses (the block then stays where it was).
  bool put(std::uint64_t key, const Voxels& voxels, std::uint32_t surface_points,
           std::uint64_t touched_in, std::string& error);
  // The stored block with this key, or nullptr.
  const Stored* find(std::uint64_t key) const {
    const auto it = index_.find(key);
    return it == index_.end() ? nullptr : &it->second;
  }
  // Reads a stored block back (any thread, with its own `scratch`); false, with `error`, when
  // the file cannot be read.
  bool read(const Stored& stored, Voxels& voxels, std::vector<std::uint8_t>& scratch,
            std::string& error) const;
  // What the map writes from a stored block, counted again (a neighbour left the map).
  void setSurfacePoints(std::uint64_t key, std::uint32_t points) {
    const auto it = index_.find(key);
    if (it != index_.end()) it.value().surface_points = points;
  }
  // Forgets a block (taken back into memory, or replaced).
  void erase(std::uint64_t key);
  const Index& blocks() const { return index_; }
  std::size_t size() const { return index_.size(); }
  bool empty() const { return index_.empty(); }
  // Bytes of the scratch file, and of the blocks stored in it.
  std::uint64_t fileBytes() const { return file_ ? file_->bytes() : 0; }
  std::uint64_t storedBytes() const { return stored_bytes_; }
  // The index's memory.
  std::size_t memoryBytes() const {
    return index_.bucket_count() * (sizeof(std::uint64_t) + sizeof(Stored) + 8);
  }
  // Forgets every block; the file goes with them.
  void clear();

 private:
  // Writes the stored blocks into a new file, leaving out what was taken back.
  bool compact(std::string& error);

  std::uint64_t compact_above_;
  Index index_;
  // Shared by copies of the map (a copy appends after what either wrote).
  std::shared_ptr<SpillFile> file_;
  std::uint64_t stored_bytes_ = 0;
  std::vector<std::uint8_t> encoded_, scratch_;  // put()'s buffers
};

}  // namespace rgbdmap
