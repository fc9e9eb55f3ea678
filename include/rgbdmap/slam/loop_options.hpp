#pragma once

#include "rgbdmap/base/option_keys.hpp"

namespace rgbdmap {

// The tunables of loop closure (config section "loop"): place recognition among earlier
// keyframes, its geometric checks and the pose graph. How the map follows the graph is the
// mapping layer's (RefusionOptions, keys loop.refusion_*, loop.keyframe_*). Defaults are the
// measured ones (docs/loop-closure.md).
struct LoopOptions {
  bool enabled = true;  // off: odometry only, one map in the odometry frame (as before loops)

  // Candidates: earlier keyframes, not among the most recent ones (odometry links those), whose
  // estimated pose is near the new keyframe's and looks the same way. The radius and the angle
  // grow with the path walked between the two, as odometry drift does.
  int recent_keyframes = 10;
  double search_radius = 0.6;     // m
  double max_view_angle = 0.70;   // rad between the optical axes
  double drift_per_metre = 0.08;  // m (and rad) of allowance per metre walked between the two
  int max_candidates = 3;         // the best-matching few are verified geometrically
  // A keyframe is remembered as a place only if no remembered place is this close (m, rad):
  // the database grows with the space explored, not with the time spent in it.
  double place_spacing = 0.3;
  double place_spacing_angle = 0.4;

  // Geometric verification: ORB matches, then PnP RANSAC, then the dense aligner from the PnP
  // pose; the two must agree, and the dense alignment must pass the tracker's checks.
  int min_matches = 40;  // ratio-test ORB matches a candidate needs to be tried
  int min_inliers = 35;  // PnP RANSAC inliers
  double min_overlap = 0.35;
  // Pyramid level and depth weight of the dense check. Finer levels and depth residuals did not
  // make loops on real frames (fr1/rpy) more accurate (docs/loop-closure.md); they cost memory.
  int finest_level = 2;
  double depth_weight = 0.0;
  double max_distance = 0.25;  // m: a loop joins keyframes at most this far apart (measured)
  double max_disagreement_translation = 0.02;  // m between the PnP and the dense pose
  double max_disagreement_rotation = 0.035;    // rad

  // Consistency: a loop is accepted only when another one, found from a keyframe within
  // `consistency_keyframes` of it, puts the newer keyframe at the same corrected pose.
  int consistency_keyframes = 4;
  double consistent_translation = 0.03;  // m
  double consistent_rotation = 0.035;    // rad
  // After optimising, a loop whose whitened residual stays above this is taken out again.
  double max_loop_residual = 5.0;
  // A loop optimises the keyframes since the last loop closed before it, and at least this many
  // of the newest, with this many more before them as a margin; older ones stay where earlier
  // loops put them. A camera going over old ground closes a loop every few keyframes, and
  // optimising every keyframe of an hour's patrol each time would grow without bound.
  int optimise_window = 300;

  // The local window: each new keyframe is also aligned densely to this many keyframes before it
  // (beyond the one it was tracked against; 0: none), and the newest window_optimise keyframes
  // are optimised with those edges. An alignment counts when it sees window_min_overlap of the
  // earlier keyframe and moves the pair less than window_max_change_* from the graph's estimate.
  // Measured in docs/benchmarks.md (Tracking: the local window).
  // Aligned at 320 x 240 (level 1), finer than the tracker, and so gated more tightly: on
  // rendered floors a finer pair is millimetres better than odometry, on real fast turns it is
  // not, and the tight gate keeps those out.
  int window_keyframes = 4;
  int window_finest_level = 1;  // pyramid level the window aligns down to; -1: the tracker's
  int window_optimise = 20;
  double window_min_overlap = 0.4;
  double window_max_change_translation = 0.005;  // m
  double window_max_change_rotation = 0.01;      // rad

  // The floor: each keyframe that sees it (a large plane near where the graph puts the floor, or
  // before there is one, the largest level-ish plane well below the first camera) is tied to one
  // world floor, with these standard deviations of its height over it and of its tilt. Odometry
  // and the local window leave a slow drift in height and tilt that a floor seen from far off
  // turns into centimetres; the floor has none (docs/loop-closure.md).
  bool floor = true;
  double floor_sigma_height = 0.0025;  // m
  double floor_sigma_tilt = 0.0015;    // rad

  // Each edge's information is the aligner's per-pixel information times this many pixels: the
  // number of independent measurements an alignment is worth (neighbouring pixels are not
  // independent, so far fewer than the pixels used).
  double edge_pixels = 50.0;
};

Keys loopKeys(LoopOptions& o);

}  // namespace rgbdmap
