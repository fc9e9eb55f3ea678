#include "rgbdmap/runtime/unmapped_frames.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

namespace rgbdmap {

UnmappedFrames UnmappedFrames::of(const RunStats& stats, std::vector<SkipReasons::Entry> reasons) {
  UnmappedFrames f;
  f.delivered = stats.frames_captured.load();
  f.skipped = stats.frames_skipped.load();
  f.without_pose = stats.frames_without_pose.load();
  f.keyframes = stats.keyframes.load();
  f.reasons = std::move(reasons);
  return f;
}

int UnmappedFrames::report(bool stopped_on_request) const {
  std::vector<SkipReasons::Entry> all = reasons;
  std::uint64_t explained = 0;
  for (const SkipReasons::Entry& e : all) explained += e.count;
  if (skipped > explained)  // a source that does not keep reasons
    all.push_back({"unusable capture (see the warnings above)", skipped - explained, ""});
  if (without_pose > 0)
    all.push_back(
        {"no pose (no ground truth within pose.max_gap, or tracking failed)", without_pose, ""});
  std::stable_sort(
      all.begin(), all.end(),
      [](const SkipReasons::Entry& a, const SkipReasons::Entry& b) { return a.count > b.count; });
  const std::uint64_t total = delivered + skipped;
  const std::uint64_t unused = skipped + without_pose;
  if (keyframes == 0) {
    if (total == 0) {
      if (stopped_on_request) {
        spdlog::info("stopped before the first frame: nothing mapped");
        return 0;
      }
      spdlog::error("nothing mapped: the source delivered no frame");
      return 1;
    }
    spdlog::error("nothing mapped: none of the {} frames could be used:{}", total,
                  describeSkipReasons(all));
    return 1;
  }
  if (unused * 2 > total)
    spdlog::warn("most frames were not mapped: {} of {} could not be used:{}", unused, total,
                 describeSkipReasons(all));
  return 0;
}

}  // namespace rgbdmap
