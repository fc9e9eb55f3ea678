#pragma once

#include <sensor_msgs/PointCloud2.h>

#include <string>

#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// A map as sensor_msgs/PointCloud2: x, y, z and PCL's packed rgb float (what rviz and
// pcl_conversions read), 16 bytes a point.
sensor_msgs::PointCloud2 toCloudMessage(const MapCloud& map, const std::string& frame_id,
                                        double stamp);
// Back from such a message (fields found by name: x, y, z as float32, rgb optional). Returns
// false, with `error` saying why, for one it cannot read.
bool fromCloudMessage(const sensor_msgs::PointCloud2& msg, MapCloud& map, std::string& error);

}  // namespace rgbdmap
