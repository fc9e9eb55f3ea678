#pragma once

#include <tsl/hopscotch_set.h>

#include <Eigen/Geometry>
#include <cstdint>

#include "rgbdmap/mapping/triangle_mesh.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"

namespace rgbdmap {

// Joins the meshes of several submaps (loop closure) into one. Submaps overlap, and a room
// walked round twice is seen by many of them, so concatenating them would show each surface
// several times over (measured: 5x the triangles on a 2.5-lap walk). Meshes are added in order
// of preference (newest first); a triangle is left out when its centre falls in a voxel that a
// triangle kept from an earlier-added mesh touches (its corners or centre), so each surface
// comes out about once, with seams where one submap's part ends and another's begins.
// Triangles of one mesh never exclude each other. Deterministic: the same meshes in the same
// order give the same result.
class MeshMerger {
 public:
  explicit MeshMerger(double voxel_size) : voxel_size_(voxel_size) {}
  void add(const TriangleMesh& mesh, const Eigen::Isometry3d& pose);
  const TriangleMesh& mesh() const { return merged_; }
  TriangleMesh take() { return std::move(merged_); }

 private:
  std::uint64_t keyOf(const Eigen::Vector3f& p) const;

  double voxel_size_;
  tsl::hopscotch_set<std::uint64_t, VoxelKeyHash> covered_;
  TriangleMesh merged_;
};

}  // namespace rgbdmap
