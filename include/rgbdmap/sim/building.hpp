#pragma once

#include <cstdint>
#include <string>

#include "rgbdmap/sim/synthetic_scene.hpp"

namespace rgbdmap {

struct BuildingOptions {
  double length = 30.0;  // m along x
  double width = 20.0;   // m along y
  double height = 2.8;   // m, floor to ceiling
  std::uint64_t seed = 1;
};

// Empty if the options make a floor, else what is wrong (too small for two rows of rooms and a
// corridor: at least 8 x 7.5 m; at most 200 x 200 m; height 2.4 to 5 m).
std::string buildingProblem(const BuildingOptions& options);

// An office floor centred on x = y = 0, floor at z = 0: a corridor along x through the middle
// with rooms on both sides (3 to 6 m wide, their depth what the corridor leaves), each with a
// door into the corridor (1.2 to 1.3 m wide, 2.1 m high, wall above it), furniture along its
// walls (desks, cabinets, crates, balls) clear of the way from the door to where a tour stops to
// look round, and the same textures as the rooms. The shell (floor, ceiling, outer walls) is the
// scene's room; inner walls are SceneWalls. The seed decides the corridor's width and place, the
// rooms' number and widths, the doors and the furniture; the same seed gives the same floor. The
// scene carries its FloorPlan for a TourPath. Throws InputError if buildingProblem() says so.
SyntheticScene generateBuilding(const BuildingOptions& options);

}  // namespace rgbdmap
