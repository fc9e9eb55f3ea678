#pragma once

#include <cstdint>
#include <mutex>
#include <vector>

#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {

// Localising: which frames were tracked before the saved map was recognised. A frame counts
// when its keyframe (anchor) comes before the keyframe the first placement was made at, so the
// count is the same in every replay, however far tracking runs ahead of the localiser. Frames
// are recorded by anchor only until tracking sees the first placement (bounded memory).
class FramesBeforePlacement {
 public:
  explicit FramesBeforePlacement(const PoseCorrections& placement) : placement_(placement) {}

  // Tracking thread, for every frame with a pose.
  void add(std::int64_t anchor);
  // After tracking and the localiser have finished: the frames anchored before `first_placed`
  // (-1: never placed, every frame).
  std::uint64_t count(std::int64_t first_placed) const;

 private:
  const PoseCorrections& placement_;
  mutable std::mutex mutex_;
  bool placed_seen_ = false;
  std::uint64_t frames_ = 0;
  std::vector<std::uint64_t> by_anchor_;  // [0]: no anchor, [k + 1]: anchor k
};

}  // namespace rgbdmap
