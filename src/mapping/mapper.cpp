#include "rgbdmap/mapping/mapper.hpp"

namespace rgbdmap {

Mapper::Mapper(const Config& config, RunStats& stats)
    : integrator_(config),
      map_(config.voxel_size, static_cast<std::uint32_t>(config.map_min_observations)),
      stats_(stats) {}

namespace {
// The point count shown while mapping is refreshed every this many keyframes (counting costs
// about a tenth of a fusion); a snapshot gives the exact count.
constexpr std::uint64_t kCountPointsEvery = 10;
}  // namespace

void Mapper::fuse(const Frame& keyframe) {
  integrator_.integrate(keyframe, map_, stats_);
  keyframes_.push_back({keyframe.timestamp, keyframe.pose});
  const std::uint64_t fused = stats_.keyframes.fetch_add(1) + 1;
  if (fused % kCountPointsEvery == 1) stats_.map_points.store(map_.pointCount());
}

std::shared_ptr<MapCloud> Mapper::snapshot() const {
  auto cloud = std::make_shared<MapCloud>();
  map_.extract(*cloud);
  stats_.map_points.store(cloud->size());  // what is written
  return cloud;
}

}  // namespace rgbdmap
