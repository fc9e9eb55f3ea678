#pragma once

#include <sensor_msgs/PointCloud2.h>

#include <cstddef>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "rgbdmap/mapping/map_cells.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// A map as sensor_msgs/PointCloud2: x, y, z and PCL's packed rgb float (what rviz and
// pcl_conversions read), 16 bytes a point. With `max_points` > 0, a bigger map is thinned to
// every k-th point so that it has at most that many (a building's map is tens of millions).
sensor_msgs::PointCloud2 toCloudMessage(const MapCloud& map, const std::string& frame_id,
                                        double stamp, std::size_t max_points = 0);
// Back from such a message (fields found by name: x, y, z as float32, rgb optional). Returns
// false, with `error` saying why, for one it cannot read.
bool fromCloudMessage(const sensor_msgs::PointCloud2& msg, MapCloud& map, std::string& error);

// What changed in a map, cell by cell (docs/ros.md, /rgbdmap/map_changes): the whole points of
// every changed cell, then one row for every cell left empty. Fields x, y, z, rgb (float32, as
// toCloudMessage's) and cell_x, cell_y, cell_z (int32: the cell spans [c, c + 1) x cell_size on
// each axis, MapCells::kCellSize); an emptied cell's row has x, y and z NaN, which PCL and rviz
// skip as an invalid point.
sensor_msgs::PointCloud2 toCellChangesMessage(const MapCloud& map, const MapCells& cells,
                                              const MapChanges::Change& change,
                                              const std::string& frame_id, double stamp);
// A consumer's copy of the map kept by cell, and what applying such a message does to it: each
// cell in the message is replaced by the message's points (none for an emptied one). Returns
// false, with `error` saying why, for a message without those fields.
using CellMap = std::map<std::tuple<int, int, int>, std::vector<pcl::PointXYZRGB>>;
bool applyCellChanges(const sensor_msgs::PointCloud2& msg, CellMap& map, std::string& error);

}  // namespace rgbdmap
