#include "rgbdmap/mapping/mapper.hpp"

#include <chrono>

namespace rgbdmap {
namespace {

KeyframeSelector makeSelector(const Config& c) {
  KeyframeSelector s;
  s.policy = c.keyframe_policy == "motion" ? KeyframeSelector::Policy::kMotion
             : c.keyframe_policy == "both" ? KeyframeSelector::Policy::kBoth
                                           : KeyframeSelector::Policy::kInterval;
  s.every_n = c.keyframe_every_n;
  s.min_translation = c.keyframe_min_translation;
  s.min_rotation = c.keyframe_min_rotation;
  return s;
}

}  // namespace

Mapper::Mapper(const Config& config, std::unique_ptr<PoseProvider> poses, RunStats& stats)
    : poses_(std::move(poses)),
      selector_(makeSelector(config)),
      integrator_(config),
      map_(config.voxel_size, static_cast<std::uint32_t>(config.map_min_observations)),
      stats_(stats),
      min_observations_(map_.minObservations()) {}

bool Mapper::process(Frame& frame) {
  const auto start = std::chrono::steady_clock::now();
  const bool posed = poses_->estimate(frame);
  stats_.pose_latency.record(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!posed) {
    stats_.frames_without_pose.fetch_add(1);
    return false;
  }
  if (!selector_.isKeyframe(posed_frames_++, frame.pose)) return false;
  integrator_.integrate(frame, map_, stats_);
  keyframes_.push_back({frame.timestamp, frame.pose});
  stats_.keyframes.fetch_add(1);
  stats_.map_points.store(map_.pointCount());  // what a snapshot writes
  return true;
}

std::shared_ptr<MapCloud> Mapper::snapshot() const {
  auto cloud = std::make_shared<MapCloud>();
  map_.extract(*cloud);
  return cloud;
}

}  // namespace rgbdmap
