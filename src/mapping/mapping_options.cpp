// The key tables of the mapping layer's option structs.
#include <stdexcept>
#include <utility>

#include "rgbdmap/mapping/depth_filter.hpp"
#include "rgbdmap/mapping/keyframe_selector.hpp"
#include "rgbdmap/mapping/map_options.hpp"

namespace rgbdmap {

Keys keyframeKeys(KeyframeOptions& o) {
  return {
      choice("keyframe.policy", &o.policy, {"auto", "interval", "motion", "both"},
             "interval: every N frames; motion: after moving; both: whichever comes first; auto: "
             "motion with odometry, else interval"),
      integer("keyframe.every_n", &o.every_n, 1, 1000000, "frames between keyframes"),
      number("keyframe.min_translation", &o.min_translation, 0, 100,
             "metres moved since the last keyframe that make a new one"),
      number("keyframe.min_rotation", &o.min_rotation, 0, 3.15,
             "radians turned since the last keyframe that make a new one"),
  };
}

Keys filterKeys(FilterOptions& o) {
  Keys keys = {
      number("filter.min_depth", &o.min_depth, 0, 100, "nearest depth used (m)"),
      number("filter.max_depth", &o.max_depth, 0.01, 100, "farthest depth used (m)"),
      choice("filter.outliers", &o.outliers, {"fast", "statistical", "none"},
             "fast: flying pixels and specks on the depth image; statistical: PCL's SOR"),
      number("filter.edge_jump", &o.edge_jump, 0.001, 1,
             "relative depth jump to a neighbour that marks a flying pixel"),
      integer("filter.speck_min_neighbours", &o.speck_min_neighbours, 0, 8,
              "neighbours (of 8) with similar depth a pixel needs to be kept"),
      boolean("filter.subsample", &o.subsample,
              "fuse every 2nd pixel of each row and column where 2 pixels span under half a voxel"),
      integer("filter.smooth_radius", &o.smooth_radius, 0, 10,
              "half-size of the edge-aware inverse-depth averaging window (0 = off)"),
      number("filter.smooth_range", &o.smooth_range, 0.001, 1,
             "a smoothing window whose depth spread is over this share of its depth (plus "
             "filter.smooth_noise_sigmas) straddles an edge: its pixel is not fused"),
      number("filter.smooth_noise_sigmas", &o.smooth_noise_sigmas, 0, 20,
             "depth noise sigmas (Kinect model) a smoothing window's spread may have besides "
             "filter.smooth_range"),
      integer("filter.sor_mean_k", &o.sor_mean_k, 1, 1000,
              "statistical outlier removal: neighbours"),
      number("filter.sor_stddev", &o.sor_stddev, 0, 100, "statistical outlier removal: sigma"),
  };
  // Either end of the range may be set first; the range must stay non-empty.
  for (Key& k : keys)
    if (k.name == "filter.min_depth" || k.name == "filter.max_depth")
      k = checked(std::move(k), [&o] {
        if (o.min_depth >= o.max_depth)
          throw std::invalid_argument("filter.min_depth must be below filter.max_depth");
      });
  return keys;
}

Keys mapKeys(MapOptions& o) {
  return {
      number("map.voxel_size", &o.voxel_size, 0.001, 10, "voxel edge (m)"),
      integer("map.min_observations", &o.min_observations, 1, 255,
              "voxels seen in fewer frames are left out of written maps"),
      number("map.truncation", &o.truncation, 0.001, 10,
             "narrowest band around a measured surface that fusion updates (m)"),
      number("map.truncation_sigmas", &o.truncation_sigmas, 0, 100,
             "band around a measured surface in units of its depth noise sigma(z), if wider"),
      number("map.min_incidence_cosine", &o.min_incidence_cosine, 0.01, 1,
             "distances along a grazing line of sight are scaled by cos(incidence), clamped at "
             "this (1 = distances along the ray)"),
      integer("map.fusion_threads", &o.fusion_threads, 0, 256,
              "threads that update voxels (0 = every core when replaying, 1 with a live camera)"),
      number("map.memory", &o.memory, 0, 1000000,
             "MB of map blocks in memory; beyond it those the camera left longest ago move to a "
             "scratch file on disk (in TMPDIR, else /tmp) and come back when it returns; every "
             "map written is still the whole map (0 = no limit)"),
  };
}

Keys refusionKeys(RefusionOptions& o) {
  return {
      number("loop.refusion_shift", &o.refusion_shift, 0.0001, 1,
             "with loop closure: the map is fused again once a loop moves a kept keyframe this "
             "far (m, a point 2 m in front of it)"),
      integer("loop.refusion_pace", &o.refusion_pace, 1, 1000,
              "with loop closure: keyframes fused again per new keyframe while the map follows a "
              "loop"),
      number("loop.keyframe_memory", &o.keyframe_memory, 1, 1000000,
             "with loop closure: MB of kept keyframe images in memory (for re-fusion); beyond "
             "it a view another kept keyframe shares is let go, and the oldest unique ones move "
             "to a scratch file on disk (in TMPDIR, else /tmp)"),
      number("loop.region_share", &o.region_share, 0, 1,
             "with loop closure: a pass fuses again only the region the loop moved, from the "
             "kept keyframes that see it, when they are at most this share of the kept ones; "
             "else the whole map (0: always the whole map)"),
  };
}

}  // namespace rgbdmap
