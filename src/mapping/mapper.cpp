#include "rgbdmap/mapping/mapper.hpp"

namespace rgbdmap {

Mapper::Mapper(const Config& config, RunStats& stats)
    : integrator_(config),
      map_(config.voxel_size, static_cast<std::uint32_t>(config.map_min_observations)),
      stats_(stats) {}

void Mapper::fuse(const Frame& keyframe) {
  integrator_.integrate(keyframe, map_, stats_);
  keyframes_.push_back({keyframe.timestamp, keyframe.pose});
  stats_.keyframes.fetch_add(1);
  stats_.map_points.store(map_.pointCount());  // what a snapshot writes
}

std::shared_ptr<MapCloud> Mapper::snapshot() const {
  auto cloud = std::make_shared<MapCloud>();
  map_.extract(*cloud);
  return cloud;
}

}  // namespace rgbdmap
