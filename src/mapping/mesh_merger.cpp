#include "rgbdmap/mapping/mesh_merger.hpp"

#include <cmath>
#include <vector>

namespace rgbdmap {

std::uint64_t MeshMerger::keyOf(const Eigen::Vector3f& p) const {
  // 21 bits per axis as the map's keys; wraps beyond ±10 km at 1 cm, where a collision only
  // drops a triangle of an overlapping submap.
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const auto v =
        static_cast<std::int64_t>(std::floor(static_cast<double>(p[axis]) / voxel_size_));
    key |= (static_cast<std::uint64_t>(v + (1 << 20)) & 0x1fffff) << (21 * axis);
  }
  return key;
}

void MeshMerger::add(const TriangleMesh& mesh, const Eigen::Isometry3d& pose) {
  const Eigen::Isometry3f moved = pose.cast<float>();
  std::vector<Eigen::Vector3f> vertices(mesh.vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) vertices[i] = moved * mesh.vertices[i];
  // This mesh's vertices renumbered as they are first used by a kept triangle (UINT32_MAX: not
  // yet), so that the vertices of left-out triangles are not written.
  std::vector<std::uint32_t> renumbered(vertices.size(), UINT32_MAX);
  std::vector<std::uint64_t> touched;  // voxels this mesh covers, excluded for later meshes
  for (const TriangleMesh::Triangle& t : mesh.triangles) {
    const Eigen::Vector3f centre = (vertices[t[0]] + vertices[t[1]] + vertices[t[2]]) / 3.0f;
    if (covered_.count(keyOf(centre)) != 0) continue;
    TriangleMesh::Triangle kept;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& to = renumbered[t[k]];
      if (to == UINT32_MAX) {
        to = static_cast<std::uint32_t>(merged_.vertices.size());
        merged_.vertices.push_back(vertices[t[k]]);
        merged_.colours.push_back(mesh.colours[t[k]]);
      }
      kept[k] = to;
      touched.push_back(keyOf(vertices[t[k]]));
    }
    touched.push_back(keyOf(centre));
    merged_.triangles.push_back(kept);
  }
  covered_.insert(touched.begin(), touched.end());
}

}  // namespace rgbdmap
