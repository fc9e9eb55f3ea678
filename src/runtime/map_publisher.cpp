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

void MapPublication::afterFrame(const Frame& frame, TrackingState state, const RunStats& stats,
                                bool keyframe) {
  if (!publisher_) return;
  PublishedStatus status;
  status.frames_processed = stats.frames_processed.load();
  status.frames_dropped = stats.frames_dropped.load();
  status.keyframes = stats.keyframes.load();
  status.map_points = stats.map_points.load();
  status.tracking = state;
  status.keyframe = keyframe;
  publisher_->publishFrame(frame, status);
}

bool MapPublication::mapDue(const RunStats& stats) {
  if (!publisher_) return false;
  const std::uint64_t keyframes = stats.keyframes.load();
  if (keyframes == keyframes_published_ || !publisher_->wantsMap()) return false;
  if (now() < next_map_at_.load()) return false;
  keyframes_published_ = keyframes;
  // Spaced further once this one has been extracted and its cost is known.
  next_map_at_.store(now() + min_interval_);
  return true;
}

void MapPublication::publishMap(const Mapper& mapper) {
  const double start = now();
  publisher_->publishUp(mapper.upEvidence());
  publisher_->publishMap(mapper.snapshot());
  const double took = now() - start;
  next_map_at_.store(start + std::max(min_interval_, took / max_share_));
}

void MapPublication::atEnd(std::shared_ptr<const MapCloud> map, const UpEvidence& up) {
  if (!publisher_) return;
  publisher_->publishUp(up);
  publisher_->publishMap(std::move(map));
}

}  // namespace rgbdmap
