#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "rgbdmap/tracking/dense_aligner.hpp"

namespace rgbdmap {

// An alignment reference kept for a long time (a place of loop closure, a saved session's) at
// half the size: 8 bytes a point instead of 16. Places are kept for the whole run, and on a
// patrol their references are most of what grows with its length. Coordinates in steps of
// 1/4096 m (x and y within +-8 m, depth up to 16 m: points beyond are left out), intensity in
// steps of 1/256 of a grey level: a tenth of a millimetre is far below a depth camera's noise,
// and steps that are powers of two make expanding and packing again give back the same bits
// (a session read and written again is the same file).
struct PackedReference {
  struct Point {
    std::int16_t x = 0, y = 0;
    std::uint16_t z = 0, intensity = 0;
  };
  struct Level {
    LevelCamera camera;
    std::vector<Point> points;
  };
  std::vector<Level> levels;
  int valid_pixels = 0;  // as AlignmentReference's

  static PackedReference pack(const AlignmentReference& reference);
  // Into `out`, reusing its buffers (a place is expanded for each verification).
  void expand(AlignmentReference& out) const;
  std::size_t points() const;
  std::size_t memoryBytes() const;
};

}  // namespace rgbdmap
