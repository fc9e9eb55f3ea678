#pragma once

#include <cstddef>
#include <cstdint>

namespace rgbdmap {

// Mixes all bits of a packed key: the identity hash std::hash gives integers puts neighbouring
// blocks into neighbouring buckets, which overflows hopscotch neighbourhoods.
struct VoxelKeyHash {
  std::size_t operator()(std::uint64_t key) const {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    key *= 0xc4ceb9fe1a85ec53ULL;
    key ^= key >> 33;
    return static_cast<std::size_t>(key);
  }
};

}  // namespace rgbdmap
