#include "rgbdmap/runtime/map_publisher.hpp"

#include <algorithm>
#include <chrono>

#include "rgbdmap/mapping/mapper.hpp"

namespace rgbdmap {
namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

void MapPublication::afterFrame(const Frame& frame, const Mapper& mapper, const RunStats& stats,
                                bool keyframe) {
  if (!publisher_) return;
  PublishedStatus status;
  status.frames_processed = stats.frames_processed.load();
  status.frames_dropped = stats.frames_dropped.load();
  status.keyframes = stats.keyframes.load();
  status.map_points = stats.map_points.load();
  status.tracking = mapper.poses().state();
  status.keyframe = keyframe;
  publisher_->publishFrame(frame, status);

  if (status.keyframes == keyframes_published_ || !publisher_->wantsMap()) return;
  const double start = now();
  if (start < next_map_at_) return;
  publisher_->publishMap(mapper.snapshot());
  keyframes_published_ = status.keyframes;
  const double took = now() - start;
  next_map_at_ = start + std::max(min_interval_, took / max_share_);
}

void MapPublication::atEnd(std::shared_ptr<const MapCloud> map) {
  if (publisher_) publisher_->publishMap(std::move(map));
}

}  // namespace rgbdmap
