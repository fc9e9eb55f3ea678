#include "rgbdmap/mapping/mesh_extractor.hpp"

#include <tsl/hopscotch_map.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "marching_cubes_tables.hpp"

namespace rgbdmap {
namespace {

// The map's hash: packed keys of neighbouring blocks or voxels are close integers, which an
// identity hash would pile into the same hopscotch neighbourhoods (measured: 4x slower).
using KeyIndex = tsl::hopscotch_map<std::uint64_t, std::uint32_t, VoxelKeyHash>;

constexpr int kEdge = VoxelMap::kBlockEdge;
constexpr int kSpan = kEdge + 1;  // a block's cells reach one voxel into the next blocks
constexpr int kGathered = kSpan * kSpan * kSpan;

std::uint64_t blockKey(const Eigen::Vector3i& block_coords) {
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis)
    key |= (static_cast<std::uint64_t>(block_coords[axis] + (1 << 20)) & 0x1fffff) << (21 * axis);
  return key;
}

// The voxels a block's 512 cells need: the block and one layer of its +x, +y, +z neighbours,
// copied into one 9x9x9 array so the cell loop never looks blocks up.
struct Neighbourhood {
  float sdf[kGathered];
  bool usable[kGathered];  // observed often enough to be trusted
  const VoxelMap::Voxel* voxel[kGathered];
  // Identifies the voxel map-wide for welding: block index * 512 + voxel index in the block.
  std::uint64_t id[kGathered];
};

void gather(const VoxelMap& map, const KeyIndex& index, std::uint32_t block_index,
            Neighbourhood& n) {
  const Eigen::Vector3i coords = map.block(block_index).origin / kEdge;
  std::uint32_t around[8];  // by (dx | dy << 1 | dz << 2), UINT32_MAX where there is none
  for (int i = 0; i < 8; ++i) {
    const auto it = index.find(blockKey(coords + Eigen::Vector3i(i & 1, (i >> 1) & 1, i >> 2)));
    around[i] = it == index.end() ? UINT32_MAX : it->second;
  }
  const auto min_observations = map.minObservations();
  for (int z = 0; z < kSpan; ++z) {
    for (int y = 0; y < kSpan; ++y) {
      for (int x = 0; x < kSpan; ++x) {
        const int at = (z * kSpan + y) * kSpan + x;
        const std::uint32_t b = around[(x >> 3) | ((y >> 3) << 1) | ((z >> 3) << 2)];
        if (b == UINT32_MAX) {
          n.usable[at] = false;
          continue;
        }
        const int local = ((z & 7) * kEdge + (y & 7)) * kEdge + (x & 7);
        const VoxelMap::Voxel& v = map.block(b).voxels[local];
        n.sdf[at] = v.sdf();
        n.usable[at] = v.observed() && v.observations >= min_observations;
        n.voxel[at] = &v;
        n.id[at] = static_cast<std::uint64_t>(b) * VoxelMap::kBlockVoxels + local;
      }
    }
  }
}

// Builds the mesh of a map: the blocks indexed by coordinates, which of them hold a voxel near
// the zero level, and the vertices welded by edge.
class MeshBuilder {
 public:
  MeshBuilder(const VoxelMap& map, const MeshOptions& options)
      : map_(map),
        voxel_(static_cast<float>(map.voxelSize())),
        max_near_(options.max_near_voxels * voxel_),
        max_jump_(options.max_jump_voxels * voxel_),
        slots_(static_cast<std::uint32_t>(map.blockSlots())) {
    // Slots of pruned blocks are skipped: they are in no index and near nothing.
    index_.reserve(map.blockCount());
    for (std::uint32_t b = 0; b < slots_; ++b)
      if (map.block(b).in_use) index_.emplace(blockKey(map.block(b).origin / kEdge), b);
    // Blocks with a voxel near enough to the zero level to end a trusted crossing. Most blocks
    // of the band around a surface have none, and a block's cells only reach into the blocks at
    // +1 along each axis: when none of those 8 has one, the block is skipped without gathering.
    near_.assign(slots_, false);
    for (std::uint32_t b = 0; b < slots_; ++b)
      if (map.block(b).in_use)
        for (const VoxelMap::Voxel& v : map.block(b).voxels)
          if (v.observed() && std::abs(v.sdf()) < max_near_) {
            near_[b] = true;
            break;
          }
    for (int c = 0; c < 8; ++c)
      corner_offset_[c] =
          (kCubeCorner[c][2] * kSpan + kCubeCorner[c][1]) * kSpan + kCubeCorner[c][0];
  }

  TriangleMesh build() {
    Neighbourhood n;
    for (std::uint32_t b = 0; b < slots_; ++b) {
      if (!map_.block(b).in_use || !nearAround(b)) continue;
      gather(map_, index_, b, n);
      const Eigen::Vector3i origin = map_.block(b).origin;
      for (int z = 0; z < kEdge; ++z)
        for (int y = 0; y < kEdge; ++y)
          for (int x = 0; x < kEdge; ++x) meshCell(n, origin, (z * kSpan + y) * kSpan + x);
    }
    return std::move(mesh_);
  }

 private:
  bool nearAround(std::uint32_t b) const {
    const Eigen::Vector3i coords = map_.block(b).origin / kEdge;
    for (int i = 0; i < 8; ++i) {
      const auto it = index_.find(blockKey(coords + Eigen::Vector3i(i & 1, (i >> 1) & 1, i >> 2)));
      if (it != index_.end() && near_[it->second]) return true;
    }
    return false;
  }

  // The vertex on the edge from voxel `a` to `b` (along `axis`), welded: keyed by its lower
  // voxel's id and the edge's axis.
  std::uint32_t vertexOn(const Neighbourhood& n, const Eigen::Vector3i& origin, int a, int b,
                         int axis) {
    const auto [it, inserted] =
        welded_.try_emplace(n.id[a] * 3 + static_cast<std::uint64_t>(axis),
                            static_cast<std::uint32_t>(mesh_.vertices.size()));
    if (!inserted) return it->second;
    const float t = n.sdf[a] / (n.sdf[a] - n.sdf[b]);  // signs differ: never 0/0
    const int x = a % kSpan, y = (a / kSpan) % kSpan, z = a / (kSpan * kSpan);
    Eigen::Vector3f p = (origin + Eigen::Vector3i(x, y, z)).cast<float>();
    p[axis] += t;
    mesh_.vertices.push_back((p + Eigen::Vector3f::Constant(0.5f)) * voxel_);  // voxel centres
    const VoxelMap::Voxel &va = *n.voxel[a], &vb = *n.voxel[b];
    auto mix = [t](std::uint8_t from, std::uint8_t to) {
      return static_cast<std::uint8_t>(std::lround(from + t * (static_cast<float>(to) - from)));
    };
    mesh_.colours.push_back({mix(va.r, vb.r), mix(va.g, vb.g), mix(va.b, vb.b)});
    return it->second;
  }

  // The triangles of the cell whose lowest corner is voxel `base` of `n`.
  void meshCell(const Neighbourhood& n, const Eigen::Vector3i& origin, int base) {
    int signs = 0;
    bool usable = true;
    for (int c = 0; c < 8 && usable; ++c) {
      const int at = base + corner_offset_[c];
      usable = n.usable[at];
      if (n.sdf[at] < 0.0f) signs |= 1 << c;
    }
    if (!usable || signs == 0 || signs == 0xff) return;
    // Every crossed edge must look like a surface (MeshOptions), or the cell is left out.
    for (int e = 0; e < 12; ++e) {
      const int c0 = kCubeEdge[e][0], c1 = kCubeEdge[e][1];
      if (((signs >> c0) & 1) == ((signs >> c1) & 1)) continue;
      const float s0 = n.sdf[base + corner_offset_[c0]], s1 = n.sdf[base + corner_offset_[c1]];
      if (!(std::min(std::abs(s0), std::abs(s1)) < max_near_ && std::abs(s0 - s1) < max_jump_))
        return;
    }
    std::uint32_t on_edge[12];
    for (int e = 0; e < 12; ++e) {
      int c0 = kCubeEdge[e][0], c1 = kCubeEdge[e][1];
      if (((signs >> c0) & 1) == ((signs >> c1) & 1)) continue;
      // Welded by the edge's lower end, whichever cell meets the edge first.
      if (corner_offset_[c0] > corner_offset_[c1]) std::swap(c0, c1);
      int axis = 0;
      while (kCubeCorner[c0][axis] == kCubeCorner[c1][axis]) ++axis;
      on_edge[e] = vertexOn(n, origin, base + corner_offset_[c0], base + corner_offset_[c1], axis);
    }
    // The table winds its triangles clockwise seen from the positive side (with this corner
    // numbering); reversed, they face the free space the camera looked through.
    const std::int8_t* row = kTriangleTable[signs];
    for (int i = 0; row[i] >= 0; i += 3)
      mesh_.triangles.push_back({on_edge[row[i]], on_edge[row[i + 2]], on_edge[row[i + 1]]});
  }

  const VoxelMap& map_;
  const float voxel_, max_near_, max_jump_;
  const std::uint32_t slots_;
  KeyIndex index_;
  std::vector<bool> near_;
  KeyIndex welded_;
  int corner_offset_[8];
  TriangleMesh mesh_;
};

}  // namespace

TriangleMesh extractMesh(const VoxelMap& map, const MeshOptions& options) {
  return MeshBuilder(map, options).build();
}

}  // namespace rgbdmap
