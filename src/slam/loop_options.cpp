#include "rgbdmap/slam/loop_options.hpp"

namespace rgbdmap {

Keys loopKeys(LoopOptions& o) {
  return {
      boolean("loop.enabled", &o.enabled,
              "close loops (dense tracking only): place recognition, pose graph, map follows; "
              "false: odometry only"),
      integer("loop.recent_keyframes", &o.recent_keyframes, 1, 100000,
              "the most recent tracking keyframes are not loop candidates"),
      number("loop.place_spacing", &o.place_spacing, 0, 100,
             "a keyframe is kept for later loops unless a kept one is this near (m) and turned "
             "less than loop.place_spacing_angle"),
      number("loop.place_spacing_angle", &o.place_spacing_angle, 0, 3.15,
             "see loop.place_spacing (rad; 0: keep every keyframe as a place)"),
      number("loop.search_radius", &o.search_radius, 0, 100,
             "loop candidates lie this close to the keyframe's estimate (m), plus drift allowance"),
      number("loop.max_view_angle", &o.max_view_angle, 0, 3.15,
             "loop candidates look within this angle of the keyframe's direction (rad)"),
      number("loop.drift_per_metre", &o.drift_per_metre, 0, 10,
             "allowance for odometry drift per metre walked between candidate and keyframe"),
      integer("loop.max_candidates", &o.max_candidates, 1, 100,
              "best-matching candidates verified geometrically per keyframe"),
      integer("loop.min_matches", &o.min_matches, 6, 10000,
              "ORB ratio-test matches a candidate needs"),
      integer("loop.min_inliers", &o.min_inliers, 6, 10000, "PnP RANSAC inliers a loop needs"),
      number("loop.min_overlap", &o.min_overlap, 0, 1,
             "share of the candidate's pixels the dense verification must see"),
      integer("loop.finest_level", &o.finest_level, 0, 6,
              "finest pyramid level of the dense loop check (0: full resolution)"),
      number("loop.depth_weight", &o.depth_weight, 0, 100,
             "weight of the depth residual in the dense loop check"),
      number("loop.max_distance", &o.max_distance, 0, 100,
             "a loop joins two keyframes at most this far apart, as measured (m)"),
      number("loop.max_disagreement_translation", &o.max_disagreement_translation, 0, 10,
             "PnP and dense verification must agree within this (m)"),
      number("loop.max_disagreement_rotation", &o.max_disagreement_rotation, 0, 3.15,
             "PnP and dense verification must agree within this (rad)"),
      integer("loop.consistency_keyframes", &o.consistency_keyframes, 1, 1000,
              "a loop needs a consistent one from a keyframe at most this many keyframes away"),
      number("loop.consistent_translation", &o.consistent_translation, 0, 10,
             "two loops are consistent when they correct a keyframe to within this (m)"),
      number("loop.consistent_rotation", &o.consistent_rotation, 0, 3.15,
             "two loops are consistent when they correct a keyframe to within this (rad)"),
      number("loop.max_loop_residual", &o.max_loop_residual, 0, 1e6,
             "a loop whose whitened residual stays above this after optimising is removed"),
      integer("loop.optimise_window", &o.optimise_window, 1, 100000000,
              "a loop optimises the keyframes since the last loop and this many more (and at "
              "least this many newest); older ones stay put"),
      integer("loop.window_keyframes", &o.window_keyframes, 0, 100,
              "each new keyframe is aligned to this many keyframes before it too (0: only to the "
              "one it was tracked against)"),
      integer("loop.window_finest_level", &o.window_finest_level, -1, 6,
              "finest pyramid level of the window's alignments (-1: tracking.finest_level)"),
      integer("loop.window_optimise", &o.window_optimise, 2, 100000,
              "keyframes optimised after a new keyframe's window alignments"),
      number("loop.window_min_overlap", &o.window_min_overlap, 0, 1,
             "share of the earlier keyframe's pixels a window alignment must see"),
      boolean("loop.floor", &o.floor,
              "tie each keyframe that sees the floor to one world floor in the pose graph (no "
              "drift in height or tilt); false: relative motions only"),
      number("loop.floor_sigma_height", &o.floor_sigma_height, 1e-5, 1,
             "standard deviation of a keyframe's measured height over the floor (m)"),
      number("loop.floor_sigma_tilt", &o.floor_sigma_tilt, 1e-6, 1,
             "standard deviation of a keyframe's measured tilt against the floor (rad)"),
      number("loop.window_max_change_translation", &o.window_max_change_translation, 0, 10,
             "a window alignment may move the pair this far from the graph's estimate (m)"),
      number("loop.window_max_change_rotation", &o.window_max_change_rotation, 0, 3.15,
             "a window alignment may turn the pair this far from the graph's estimate (rad)"),
      number("loop.edge_pixels", &o.edge_pixels, 0.001, 1e9,
             "independent pixels an alignment is worth (scales every edge's information)"),
  };
}

}  // namespace rgbdmap
