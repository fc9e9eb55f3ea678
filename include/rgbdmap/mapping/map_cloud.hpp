#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <vector>

namespace rgbdmap {

// The map as users get it: one coloured point per surface voxel, what checkpoints write as PCD.
using MapCloud = pcl::PointCloud<pcl::PointXYZRGB>;

// A map's point as a PCD stores it: 16 bytes, half of MapCloud's (which pads each point for
// aligned access). For a copy of the map kept a while: the map a re-fusion pass began from.
struct PackedMapPoint {
  float x = 0, y = 0, z = 0;
  std::uint8_t b = 0, g = 0, r = 0, a = 255;
};
static_assert(sizeof(PackedMapPoint) == 16, "a packed point is 16 bytes");
using PackedMapCloud = std::vector<PackedMapPoint>;

// A map point of either kind (MapCloud's pcl::PointXYZRGB or PackedMapPoint) at `position` with
// colour r, g, b: the one place their fields are written, from a voxel or from another point.
template <typename Point>
Point mapPoint(float x, float y, float z, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  Point point;
  point.x = x;
  point.y = y;
  point.z = z;
  point.r = r;
  point.g = g;
  point.b = b;
  return point;
}

// The packed points as a MapCloud (what writers and viewers take).
inline MapCloud toMapCloud(const PackedMapCloud& packed) {
  MapCloud cloud;
  cloud.reserve(packed.size());
  for (const PackedMapPoint& p : packed)
    cloud.push_back(mapPoint<pcl::PointXYZRGB>(p.x, p.y, p.z, p.r, p.g, p.b));
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
  return cloud;
}

}  // namespace rgbdmap
