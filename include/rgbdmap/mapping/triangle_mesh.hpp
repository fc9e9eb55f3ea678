#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

namespace rgbdmap {

// A coloured, indexed triangle mesh (what `--mesh` writes as PLY): one colour per vertex,
// triangles as three vertex indices, counter-clockwise seen from the observed (free) side.
// Plain arrays (27 bytes a vertex, 12 a triangle): a room's mesh has millions of triangles.
struct TriangleMesh {
  using Colour = std::array<std::uint8_t, 3>;  // r, g, b
  using Triangle = std::array<std::uint32_t, 3>;

  std::vector<Eigen::Vector3f> vertices;
  std::vector<Colour> colours;  // one per vertex
  std::vector<Triangle> triangles;

  bool empty() const { return triangles.empty(); }
  std::size_t memoryBytes() const {
    return vertices.capacity() * sizeof(Eigen::Vector3f) + colours.capacity() * sizeof(Colour) +
           triangles.capacity() * sizeof(Triangle);
  }
  // Appends `other` moved by `transform` (indices renumbered after this mesh's vertices).
  void append(const TriangleMesh& other,
              const Eigen::Isometry3f& transform = Eigen::Isometry3f::Identity());
};

}  // namespace rgbdmap
