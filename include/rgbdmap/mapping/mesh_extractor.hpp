#pragma once

#include "rgbdmap/mapping/triangle_mesh.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// Where a marching-cubes cell is trusted to hold a surface. The TSDF also changes sign where
// it should not: at a silhouette, voxels in front of the background (+band) sit next to voxels
// behind the foreground (negative), and a plain marching cubes would hang a curtain of faces
// between them. A real crossing between two voxel centres has one of them close to the zero
// level (the rule extract() uses for points) and a difference of about one voxel times the
// gradient (1 seen face on, ~2 at 60 degrees off the normal); a cell with any crossing edge
// outside these bounds is left out whole, so that no cell is meshed half.
struct MeshOptions {
  float max_near_voxels = 1.0f;  // the nearer end of a crossing edge: |sdf| < this * voxel
  float max_jump_voxels = 3.0f;  // both ends of a crossing edge: |sdf_a - sdf_b| < this * voxel
};

// Marching cubes on the zero level of the map: cells between 8 voxel centres that were all
// observed (weight > 0 and at least the map's min_observations), vertices interpolated
// linearly on the cell edges and shared by the triangles that meet there (the mesh is welded),
// colours interpolated likewise. Blocks are visited in the map's order, so the same map gives
// the same mesh, vertex for vertex.
TriangleMesh extractMesh(const VoxelMap& map, const MeshOptions& options = {});

}  // namespace rgbdmap
