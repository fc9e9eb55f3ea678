#pragma once

#include <string>

#include "rgbdmap/mapping/triangle_mesh.hpp"

namespace rgbdmap {

// Binary little-endian PLY, as MeshLab, CloudCompare, Open3D and Blender read it: `vertex` with
// float x, y, z and uchar red, green, blue; `face` with `list uchar int vertex_indices`.
// Written like the PCD map (temp file, fsync, rename, fsync of the folder), so the destination
// only ever holds a complete mesh; false with `error` naming the path and the system error.
bool writePlyAtomically(const TriangleMesh& mesh, const std::string& path, std::string& error);

// Reads a binary little-endian PLY mesh (or point cloud: no faces) with any scalar vertex
// properties (x, y, z required; red, green, blue used when there) and polygon faces (split into
// fans of triangles). Throws InputError naming the file and what is wrong (not a PLY, an
// unsupported format, truncated, an index out of range) instead of reading past the data.
TriangleMesh readPly(const std::string& path);

}  // namespace rgbdmap
