#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace rgbdmap {

// The map as users get it: one coloured point per surface voxel, what checkpoints write as PCD.
using MapCloud = pcl::PointCloud<pcl::PointXYZRGB>;

}  // namespace rgbdmap
