#pragma once

#include <string>

#include "rgbdmap/mapping/occupancy_grid.hpp"

namespace rgbdmap {

// map_server's format: G.pgm (occupied 0, free 254, unknown 205, the first row the grid's last,
// as map_saver writes it) and G.yaml beside it (image, resolution, origin [x, y, yaw] of the
// corner cell in the floor's frame, negate, occupied_thresh, free_thresh), plus, as comments that
// map_server skips, where the floor's frame lies in the map's. Each file is written atomically
// like the map; false with `error` naming the path and the system error.
bool writeGridAtomically(const OccupancyGrid& grid, const std::string& pgm_path,
                         std::string& error);
// G.yaml for G.pgm (any other name gets ".yaml" appended).
std::string gridYamlPath(const std::string& pgm_path);

// Reads a grid back as map_server would (tests, tools): the YAML's image, resolution, origin,
// negate and thresholds, the PGM's cells classified by them. Throws InputError naming the file
// and what is wrong.
OccupancyGrid readGrid(const std::string& yaml_path);

}  // namespace rgbdmap
