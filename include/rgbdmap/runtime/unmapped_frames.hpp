#pragma once

#include <cstdint>
#include <vector>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/base/skip_reasons.hpp"

namespace rgbdmap {

// What became of the frames of a finished run, said at its end. A run that mapped no frame has
// failed (unless it was asked to stop before any frame came); one that could not use most of its
// frames says so. Both name the most frequent reasons with their counts.
struct UnmappedFrames {
  std::uint64_t delivered = 0;     // frames the source delivered (stats.frames_captured)
  std::uint64_t skipped = 0;       // frames the source could not use (stats.frames_skipped)
  std::uint64_t without_pose = 0;  // delivered frames that got no pose
  std::uint64_t keyframes = 0;     // frames integrated into the map
  std::vector<SkipReasons::Entry> reasons;  // the source's reasons for its skipped frames

  static UnmappedFrames of(const RunStats& stats, std::vector<SkipReasons::Entry> reasons);
  // Logs the verdict; returns the exit code it calls for: 1 when nothing was mapped, else 0.
  int report(bool stopped_on_request) const;
};

}  // namespace rgbdmap
