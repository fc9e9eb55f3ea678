#pragma once

#include <cstdint>

namespace rgbdmap {

// Marching cubes' cube: corner i sits at kCubeCorner[i] (x, y, z offsets in voxels); edge e joins
// corners kCubeEdge[e][0] and kCubeEdge[e][1]. This is the numbering Bourke's table is written for.
constexpr int kCubeCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
constexpr int kCubeEdge[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                  {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

// Triangles for each of the 256 sign patterns (see marching_cubes_tables.cpp).
extern const std::int8_t kTriangleTable[256][16];

}  // namespace rgbdmap
