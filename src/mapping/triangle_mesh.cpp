#include "rgbdmap/mapping/triangle_mesh.hpp"

namespace rgbdmap {

void TriangleMesh::append(const TriangleMesh& other, const Eigen::Isometry3f& transform) {
  const auto offset = static_cast<std::uint32_t>(vertices.size());
  vertices.reserve(vertices.size() + other.vertices.size());
  for (const Eigen::Vector3f& v : other.vertices) vertices.push_back(transform * v);
  colours.insert(colours.end(), other.colours.begin(), other.colours.end());
  triangles.reserve(triangles.size() + other.triangles.size());
  for (const Triangle& t : other.triangles)
    triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

}  // namespace rgbdmap
