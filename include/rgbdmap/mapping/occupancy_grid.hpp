#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rgbdmap/base/option_keys.hpp"
#include "rgbdmap/mapping/ground_frame.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// The 2-D occupancy grid (config section "grid").
struct GridOptions {
  double resolution = 0.05;  // m, cell edge
  // Surfaces between these heights above the floor occupy a cell: lower ones are the floor, its
  // noise and what a robot drives over; higher ones are above the robot.
  double min_height = 0.10;  // m
  double max_height = 1.50;  // m: the robot's height
  // Surface points in a cell's height band that make it occupied (fewer are a speck of noise).
  int min_points = 3;
};

Keys gridKeys(GridOptions& o);

// A 2-D occupancy grid lying in the floor, laid out as ROS's nav_msgs/OccupancyGrid: cells row by
// row from the corner at map_from_grid's origin, x along a row, y across rows, z up.
struct OccupancyGrid {
  static constexpr std::int8_t kUnknown = -1;
  static constexpr std::int8_t kFree = 0;
  static constexpr std::int8_t kOccupied = 100;

  double resolution = 0.05;  // m
  int width = 0;             // cells along x
  int height = 0;            // cells along y
  Eigen::Isometry3d map_from_grid = Eigen::Isometry3d::Identity();
  // The grid's corner in the floor's frame (GroundFrame): what map_server's origin holds.
  Eigen::Vector2d origin_in_ground = Eigen::Vector2d::Zero();
  std::vector<std::int8_t> cells;  // width * height, row 0 first

  std::int8_t at(int x, int y) const {
    return cells[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                 static_cast<std::size_t>(x)];
  }
  std::size_t count(std::int8_t value) const;

  // A cell is occupied where the map has min_points surface points between the floor plus
  // min_height and max_height; free where the floor itself was seen (the camera looked through
  // the column down to it) and no surface at all is in the band; unknown elsewhere.
  static OccupancyGrid build(const MapCloud& map, const GroundFrame& ground,
                             const GridOptions& options);
};

}  // namespace rgbdmap
