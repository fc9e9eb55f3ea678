#include "rgbdmap/map_files/octomap_file.hpp"

#include <octomap/OcTree.h>

#include <sstream>
#include <unordered_set>

#include "rgbdmap/map_files/atomic_write.hpp"

namespace rgbdmap {

bool writeOctomapAtomically(const MapCloud& surface, const FreeSpaceMap& free_space,
                            const std::string& path, OctomapCounts& counts, std::string& error) {
  const double r = free_space.resolution();
  octomap::OcTree tree(r);
  // Free first: a surface point's hit (+0.85 in log-odds) outweighs the miss (-0.4), so a cell
  // both seen through and seen solid (a ray grazing a surface) ends up occupied.
  free_space.forEachFree([&tree, r](const Eigen::Vector3i& c) {
    tree.updateNode(octomap::point3d(static_cast<float>((c.x() + 0.5) * r),
                                     static_cast<float>((c.y() + 0.5) * r),
                                     static_cast<float>((c.z() + 0.5) * r)),
                    false, true);
  });
  std::unordered_set<octomap::OcTreeKey, octomap::OcTreeKey::KeyHash> occupied;
  for (const auto& p : surface.points) {
    octomap::OcTreeKey key;
    if (tree.coordToKeyChecked(octomap::point3d(p.x, p.y, p.z), key)) occupied.insert(key);
  }
  for (const octomap::OcTreeKey& key : occupied) tree.updateNode(key, true, true);
  tree.updateInnerOccupancy();
  std::ostringstream bytes;
  if (!tree.writeBinary(bytes)) {
    error = path + ": the OctoMap could not be serialised";
    return false;
  }
  counts = {};
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    ++(tree.isNodeOccupied(*it) ? counts.occupied : counts.free);
  return writeBytesAtomically(path, bytes.str(), error);
}

}  // namespace rgbdmap
