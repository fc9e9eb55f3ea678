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

// Blocks by number: those in memory then those on disk (VoxelMap::allBlockCoordinates()).
// Numbers name voxels map-wide for welding, and index which blocks are near the zero level.
struct BlockNumbers {
  std::vector<Eigen::Vector3i> coordinates;
  KeyIndex index;  // block key -> number
  std::uint32_t find(const Eigen::Vector3i& coords) const {
    const auto it = index.find(blockKey(coords));
    return it == index.end() ? UINT32_MAX : it->second;
  }
};

void gather(const VoxelMap& map, const BlockNumbers& numbers, std::uint32_t block,
            VoxelMap::BlockCache& cache, Neighbourhood& n) {
  const Eigen::Vector3i coords = numbers.coordinates[block];
  const VoxelMap::Block* around[8];  // by (dx | dy << 1 | dz << 2), nullptr where there is none
  std::uint32_t number[8];
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3i at = coords + Eigen::Vector3i(i & 1, (i >> 1) & 1, i >> 2);
    number[i] = numbers.find(at);
    around[i] = number[i] == UINT32_MAX ? nullptr : map.findBlock(at, cache);
  }
  const auto min_observations = map.minObservations();
  for (int z = 0; z < kSpan; ++z) {
    for (int y = 0; y < kSpan; ++y) {
      for (int x = 0; x < kSpan; ++x) {
        const int at = (z * kSpan + y) * kSpan + x;
        const int which = (x >> 3) | ((y >> 3) << 1) | ((z >> 3) << 2);
        if (around[which] == nullptr) {
          n.usable[at] = false;
          continue;
        }
        const int local = ((z & 7) * kEdge + (y & 7)) * kEdge + (x & 7);
        const VoxelMap::Voxel& v = around[which]->voxels[local];
        n.sdf[at] = v.sdf();
        n.usable[at] = v.observed() && v.observations >= min_observations;
        n.voxel[at] = &v;
        n.id[at] = static_cast<std::uint64_t>(number[which]) * VoxelMap::kBlockVoxels + local;
      }
    }
  }
}

// Builds the mesh of a map: the blocks numbered, which of them hold a voxel near the zero level,
// and the vertices welded by edge. Blocks on disk are read back a few at a time.
class MeshBuilder {
 public:
  MeshBuilder(const VoxelMap& map, const MeshOptions& options)
      : map_(map),
        voxel_(static_cast<float>(map.voxelSize())),
        max_near_(options.max_near_voxels * voxel_),
        max_jump_(options.max_jump_voxels * voxel_) {
    numbers_.coordinates = map.allBlockCoordinates();
    const auto blocks = static_cast<std::uint32_t>(numbers_.coordinates.size());
    numbers_.index.reserve(blocks);
    for (std::uint32_t b = 0; b < blocks; ++b)
      numbers_.index.emplace(blockKey(numbers_.coordinates[b]), b);
    // Blocks with a voxel near enough to the zero level to end a trusted crossing. Most blocks
    // of the band around a surface have none, and a block's cells only reach into the blocks at
    // +1 along each axis: when none of those 8 has one, the block is skipped without gathering.
    near_.assign(blocks, false);
    for (std::uint32_t b = 0; b < blocks; ++b) {
      cache_.trim();
      const VoxelMap::Block* block = map.findBlock(numbers_.coordinates[b], cache_);
      if (block == nullptr) continue;
      for (const VoxelMap::Voxel& v : block->voxels)
        if (v.observed() && std::abs(v.sdf()) < max_near_) {
          near_[b] = true;
          break;
        }
    }
    for (int c = 0; c < 8; ++c)
      corner_offset_[c] =
          (kCubeCorner[c][2] * kSpan + kCubeCorner[c][1]) * kSpan + kCubeCorner[c][0];
  }

  TriangleMesh build() {
    Neighbourhood n;
    for (std::uint32_t b = 0; b < numbers_.coordinates.size(); ++b) {
      if (!nearAround(b)) continue;
      cache_.trim();  // what gather() reads stays until the block's cells are meshed
      gather(map_, numbers_, b, cache_, n);
      const Eigen::Vector3i origin = numbers_.coordinates[b] * kEdge;
      for (int z = 0; z < kEdge; ++z)
        for (int y = 0; y < kEdge; ++y)
          for (int x = 0; x < kEdge; ++x) meshCell(n, origin, (z * kSpan + y) * kSpan + x);
    }
    return std::move(mesh_);
  }

 private:
  bool nearAround(std::uint32_t b) const {
    const Eigen::Vector3i coords = numbers_.coordinates[b];
    for (int i = 0; i < 8; ++i) {
      const std::uint32_t at = numbers_.find(coords + Eigen::Vector3i(i & 1, (i >> 1) & 1, i >> 2));
      if (at != UINT32_MAX && near_[at]) return true;
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
  BlockNumbers numbers_;
  VoxelMap::BlockCache cache_;
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
