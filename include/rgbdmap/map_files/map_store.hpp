#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>

#include "rgbdmap/mapping/map_cells.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// The map kept on disk as it grows (MAP.store/ beside MAP.pcd, docs/usage.md "The map store"), its
// points by cells of 1 m, so that a checkpoint writes only the cells whose points changed since the
// one before: a new keyframe changes the few cells it sees, a loop those it moved. A building's map
// is millions of points; rewriting its whole PCD at every checkpoint grows with the building,
// this with what changed. `rgbdmap export` writes the PCD a store holds.
//
// Files: points-G.bin, the cells' records appended one after another (cell key, point count,
// the points as a PCD holds them, 16 bytes each), and index.bin (a checked record,
// binary_record.hpp) naming the points file and where each cell's newest record starts. The
// index is renamed into place once the records it names are on disk, so the folder always holds
// the map of one whole checkpoint, after a crash or a full disk too. When the superseded records
// outweigh the current ones, the points are written anew as points-(G+1).bin and the old file
// goes.
class MapStore {
 public:
  static constexpr double kCellSize = MapCells::kCellSize;

  // What one write did.
  struct Written {
    std::size_t points = 0, cells = 0;  // in the map written
    std::size_t changed = 0;            // cells whose points were written (new or changed)
    std::size_t removed = 0;            // cells that had points and have none now
    std::uint64_t bytes = 0;            // written: records and index
    std::uint64_t file_bytes = 0;       // the points file's size after the write
    bool anew = false;                  // the points file written whole (first write, compaction)
  };

  // Writes nothing until write(); a store left there by an earlier run is replaced at the first.
  explicit MapStore(std::string path);

  // Adds what differs from the map last written (the whole map at the first write). Returns
  // false with `error` naming the file and the system error; the store then still holds the map
  // last written, and the next write compares with that one.
  bool write(const MapCloud& map, Written& written, std::string& error);
  const std::string& path() const { return path_; }

 private:
  struct Cell {
    std::uint64_t hash = 0;  // of its points, in any order
    std::uint64_t offset = 0;
    std::uint64_t count = 0;
  };
  std::string pointsFile(std::uint64_t generation) const;

  std::string path_;
  std::unordered_map<std::uint64_t, Cell> cells_;  // as the index on disk names them
  std::uint64_t generation_ = 0;                   // 0: nothing written yet by this run
  std::uint64_t file_bytes_ = 0;                   // of points-G.bin, G = generation_
};

// The map a store holds, cell by cell in key order. Throws InputError naming the folder or the
// file that is missing, truncated or corrupt.
MapCloud readMapStore(const std::string& path);

}  // namespace rgbdmap
