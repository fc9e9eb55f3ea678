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
  // TSDF blocks in memory at most (MB); beyond it the least recently updated go to a scratch file
  // on disk and come back when the camera returns (VoxelMap::keepWithin). 0: no limit.
  double memory = 64.0;
};

// With loop closure the map follows the pose graph (Mapper): fused keyframes are kept
// (KeyframeStore) and, when a loop moves them, the map is fused again from them at their corrected
// poses. Keys loop.*: they only matter with loop closure.
struct RefusionOptions {
  // A loop that moves a kept keyframe this far (a point 2 m in front of it) starts a re-fusion.
  double refusion_shift = 0.003;  // m
  // While the map is fused again: kept keyframes re-fused per new keyframe fused (and one each
  // time the fusion thread is idle), so that a replay's fusion and a live camera's tracking keep
  // their pace.
  int refusion_pace = 2;
  // Kept keyframes' images take at most this much memory; beyond it views shared with another
  // kept keyframe are let go, and the oldest unique ones move to disk (KeyframeStore).
  double keyframe_memory = 48.0;  // MB
  // A pass fuses again only the cells the keyframes a loop moved see (KeyframeFootprint), from
  // the kept keyframes that see them, when those are at most this share of the kept keyframes;
  // beyond it the whole map, which holds one TSDF where a region pass holds a second for its
  // region.
  double region_share = 0.5;
};

Keys mapKeys(MapOptions& o);
Keys refusionKeys(RefusionOptions& o);

}  // namespace rgbdmap
