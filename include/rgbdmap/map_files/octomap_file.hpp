#pragma once

#include <cstddef>
#include <string>

#include "rgbdmap/mapping/free_space_map.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// What an OctoMap written holds: its leaves at the finest resolution, after pruning merged the
// ones that agree.
struct OctomapCounts {
  std::size_t occupied = 0;
  std::size_t free = 0;
};

// A binary OctoMap (.bt, octomap::OcTree, as octovis, bt2vrml and octomap_server read it) at
// `free_space`'s resolution: occupied where the map has a surface point, free where the rays
// crossed and no surface is. Written atomically like the map; false with `error` naming the
// path and what failed.
bool writeOctomapAtomically(const MapCloud& surface, const FreeSpaceMap& free_space,
                            const std::string& path, OctomapCounts& counts, std::string& error);

}  // namespace rgbdmap
