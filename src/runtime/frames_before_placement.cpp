#include "rgbdmap/runtime/frames_before_placement.hpp"

#include <algorithm>

namespace rgbdmap {

void FramesBeforePlacement::add(std::int64_t anchor) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++frames_;
  if (placed_seen_) return;
  const PoseCorrections::Snapshot placement = placement_.snapshot();
  if (!placement.table->empty() && placement.joined) {
    placed_seen_ = true;  // later frames are anchored at or after the placement's keyframe
    return;
  }
  const auto slot = static_cast<std::size_t>(std::max<std::int64_t>(anchor, -1) + 1);
  if (by_anchor_.size() <= slot) by_anchor_.resize(slot + 1, 0);
  ++by_anchor_[slot];
}

std::uint64_t FramesBeforePlacement::count(std::int64_t first_placed) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (first_placed < 0) return frames_;
  std::uint64_t before = 0;
  const auto end = std::min(by_anchor_.size(), static_cast<std::size_t>(first_placed) + 1);
  for (std::size_t slot = 0; slot < end; ++slot) before += by_anchor_[slot];
  return before;
}

}  // namespace rgbdmap
