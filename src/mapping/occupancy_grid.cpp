#include "rgbdmap/mapping/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rgbdmap {

Keys gridKeys(GridOptions& o) {
  Keys keys = {
      number("grid.resolution", &o.resolution, 0.005, 10, "occupancy grid cell edge (m)"),
      number("grid.min_height", &o.min_height, 0, 100,
             "surfaces at least this high above the floor occupy a cell (m; lower ones are "
             "driven over)"),
      number("grid.max_height", &o.max_height, 0.01, 100,
             "surfaces up to this high above the floor occupy a cell (m): the robot's height"),
      integer("grid.min_points", &o.min_points, 1, 1000000,
              "surface points in a cell's height band that make it occupied"),
  };
  for (Key& k : keys)
    if (k.name == "grid.min_height" || k.name == "grid.max_height")
      k = checked(std::move(k), [&o] {
        if (o.min_height >= o.max_height)
          throw std::invalid_argument("grid.min_height must be below grid.max_height");
      });
  return keys;
}

std::size_t OccupancyGrid::count(std::int8_t value) const {
  return static_cast<std::size_t>(std::count(cells.begin(), cells.end(), value));
}

OccupancyGrid OccupancyGrid::build(const MapCloud& map, const GroundFrame& ground,
                                   const GridOptions& options) {
  OccupancyGrid grid;
  grid.resolution = options.resolution;
  // Points within half the lowest obstacle's height of the floor are the floor.
  const double floor_band = 0.5 * options.min_height;
  const Eigen::Isometry3d ground_from_map = ground.map_from_ground.inverse();

  // Points in the floor's frame that count (floor or obstacle); the rest only widen nothing.
  std::vector<Eigen::Vector3d> points;
  points.reserve(map.size() / 2);
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  for (const auto& p : map.points) {
    const Eigen::Vector3d q = ground_from_map * Eigen::Vector3d(p.x, p.y, p.z);
    if (q.z() < -floor_band || q.z() > options.max_height) continue;
    points.push_back(q);
    min_x = std::min(min_x, q.x());
    min_y = std::min(min_y, q.y());
    max_x = std::max(max_x, q.x());
    max_y = std::max(max_y, q.y());
  }
  if (points.empty()) return grid;

  // One empty cell of margin all round, corners on multiples of the resolution.
  const double r = options.resolution;
  const double x0 = (std::floor(min_x / r) - 1.0) * r;
  const double y0 = (std::floor(min_y / r) - 1.0) * r;
  grid.width = static_cast<int>(std::floor((max_x - x0) / r)) + 2;
  grid.height = static_cast<int>(std::floor((max_y - y0) / r)) + 2;
  grid.origin_in_ground = Eigen::Vector2d(x0, y0);
  grid.map_from_grid = ground.map_from_ground * Eigen::Translation3d(x0, y0, 0.0);

  const std::size_t n =
      static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height);
  std::vector<std::uint32_t> obstacle_points(n, 0);
  std::vector<bool> floor_seen(n, false);
  for (const Eigen::Vector3d& q : points) {
    const int x = std::clamp(static_cast<int>(std::floor((q.x() - x0) / r)), 0, grid.width - 1);
    const int y = std::clamp(static_cast<int>(std::floor((q.y() - y0) / r)), 0, grid.height - 1);
    const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(grid.width) +
                          static_cast<std::size_t>(x);
    if (q.z() >= options.min_height)
      ++obstacle_points[i];
    else if (q.z() <= floor_band)
      floor_seen[i] = true;
  }
  grid.cells.assign(n, kUnknown);
  for (std::size_t i = 0; i < n; ++i) {
    if (obstacle_points[i] >= static_cast<std::uint32_t>(options.min_points))
      grid.cells[i] = kOccupied;
    else if (floor_seen[i] && obstacle_points[i] == 0)  // a speck makes it unknown, not free
      grid.cells[i] = kFree;
  }
  // The floor seen ends about a cell short of where the camera saw it: the map fuses keyframes,
  // a few centimetres apart, and the edges of the views between them fall in no keyframe. A cell
  // next to seen floor, empty itself and next to nothing occupied, is free too.
  const std::vector<std::int8_t> seen = grid.cells;
  const auto at = [&](int x, int y) {
    return seen[static_cast<std::size_t>(y) * static_cast<std::size_t>(grid.width) +
                static_cast<std::size_t>(x)];
  };
  for (int y = 1; y + 1 < grid.height; ++y)
    for (int x = 1; x + 1 < grid.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(grid.width) +
                            static_cast<std::size_t>(x);
      if (seen[i] != kUnknown || obstacle_points[i] > 0) continue;
      bool next_to_floor = false, next_to_obstacle = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const std::int8_t c = at(x + dx, y + dy);
          next_to_obstacle = next_to_obstacle || c == kOccupied;
          next_to_floor = next_to_floor || (c == kFree && (dx == 0 || dy == 0));
        }
      if (next_to_floor && !next_to_obstacle) grid.cells[i] = kFree;
    }
  return grid;
}

}  // namespace rgbdmap
