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

// The packed points as a MapCloud (what writers and viewers take).
inline MapCloud toMapCloud(const PackedMapCloud& packed) {
  MapCloud cloud;
  cloud.resize(packed.size());
  for (std::size_t i = 0; i < packed.size(); ++i) {
    const PackedMapPoint& p = packed[i];
    pcl::PointXYZRGB& out = cloud[i];
    out.x = p.x;
    out.y = p.y;
    out.z = p.z;
    out.r = p.r;
    out.g = p.g;
    out.b = p.b;
  }
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
  return cloud;
}

}  // namespace rgbdmap
