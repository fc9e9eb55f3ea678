#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// A map's points grouped by cubes of 1 m, each with a hash of its points that ignores their
// order (the voxel map extracts blocks in an order that changes as blocks go to disk and come
// back). What a checkpoint writes (MapStore) and what ROS sends (~map_changes) are the cells
// whose hash or count changed: a new keyframe changes the few cells it sees, a loop those it
// moved.
struct MapCells {
  static constexpr double kCellSize = 1.0;  // m

  struct Cell {
    std::uint64_t hash = 0;
    std::vector<std::uint32_t> points;  // indices into the map
  };
  std::unordered_map<std::uint64_t, Cell> cells;

  static MapCells of(const MapCloud& map);

  // 21 bits per axis, offset by 2^20 cells: +-1000 km at 1 m. A point that is not finite lands
  // in the cell of the origin rather than overflow.
  static std::uint64_t keyOf(const pcl::PointXYZRGB& p);
  // The cell's integer coordinates: it spans [c, c + 1) * kCellSize on each axis.
  static Eigen::Vector3i coordinatesOf(std::uint64_t key);
};

// The cells that changed from one map to the next, remembering only each cell's hash and count.
class MapChanges {
 public:
  struct Change {
    std::vector<std::uint64_t> changed;  // new or changed cells, in key order
    std::vector<std::uint64_t> removed;  // cells that had points and have none now, in key order
  };

  // Compares `now` with the map given last (everything is new at the first call) and remembers
  // `now`. With `everything`, every cell of `now` counts as changed
  // (for a consumer that has none of it), and the removed ones are still named.
  Change next(const MapCells& now, bool everything = false);

 private:
  struct Seen {
    std::uint64_t hash = 0;
    std::size_t count = 0;
  };
  std::unordered_map<std::uint64_t, Seen> last_;
};

}  // namespace rgbdmap
