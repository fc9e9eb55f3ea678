#pragma once

#include "rgbdmap/base/option_keys.hpp"

namespace rgbdmap {

// The map (config section "map"): its voxels, what fusion updates (TsdfIntegrator) and what
// written maps keep (Mapper).
struct MapOptions {
  double voxel_size = 0.01;           // m
  int min_observations = 1;           // voxels seen fewer times are not written
  double truncation = 0.03;           // narrowest TSDF band (m)
  double truncation_sigmas = 3.0;     // band in depth-noise sigmas
  double min_incidence_cosine = 0.2;  // clamp of cos(incidence)
  int fusion_threads = 0;             // 0 = every core in a replay, 1 for a live camera
};

// With loop closure the map is fused into submaps anchored to tracking keyframes (Mapper); a new
// one starts after this many fused keyframes or this far from where the submap started. Keys
// loop.submap_*: they only matter with loop closure.
struct SubmapOptions {
  int submap_keyframes = 40;
  double submap_distance = 1.0;  // m
  double submap_rotation = 1.0;  // rad
};

Keys mapKeys(MapOptions& o);
Keys submapKeys(SubmapOptions& o);

}  // namespace rgbdmap
