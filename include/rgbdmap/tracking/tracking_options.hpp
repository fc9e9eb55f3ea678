#pragma once

#include <string>

#include "rgbdmap/base/option_keys.hpp"

namespace rgbdmap {

// The tunables of camera tracking (config section "tracking"). Defaults are the measured ones
// (see bench/track_sequence.cpp and the README's tracking table).
struct TrackingOptions {
  // dense: our photometric + geometric aligner against the last keyframe; opencv_rgbd and
  // opencv_rgbd_icp: OpenCV's RgbdOdometry / RgbdICPOdometry against a reference frame.
  std::string method = "dense";

  // Image pyramid: level 0 is full resolution, each level halves it. Alignment runs from
  // coarsest_level down to finest_level.
  int coarsest_level = 3;
  int finest_level = 2;
  // Resample the finest level to a pinhole camera when the lens distorts (key camera.undistort,
  // which sets FilterOptions::undistort too: one lens).
  bool undistort = true;
  // A rolling shutter's readout time (s; key camera.readout): the camera's motion over it, from
  // the last frame's velocity, is undone row by row. 0: a global shutter.
  double readout = 0.0;
  // Measure the readout while tracking, starting from `readout`: each alignment of a moving
  // camera says how much longer or shorter it fits best. readout_prior_weight: how much
  // information the starting value counts for (in alignments' readout information, 1/s^2).
  bool estimate_readout = true;
  double readout_prior_weight = 1e7;
  int max_iterations = 12;    // Gauss-Newton steps per level (coarse levels)
  int finest_iterations = 6;  // on the finest level, where a step costs the most
  double depth_weight = 0.1;  // weight of a (normalised) depth residual vs an intensity one
  // How a depth residual's noise varies over the image: "quadratic", with depth squared (a
  // structured-light or stereo sensor's), or "constant" (one robust scale for every pixel).
  // Measured in docs/benchmarks.md (Tracking): quadratic at 0.1 against photometric only.
  std::string depth_noise = "quadratic";
  // "offset": each alignment also estimates how much brighter the frame is than the reference
  // (one offset in grey levels, what auto-exposure changes) and takes it out of the intensity
  // residuals, less brightness_tolerance (smaller offsets are as likely a misalignment);
  // "none": intensities compared as they are. Measured in docs/benchmarks.md (Tracking).
  std::string brightness = "offset";
  double brightness_tolerance = 6.0;  // grey levels
  // On the coarse levels, where the frame starts pixels away from where it lands, an intensity
  // residual's linearisation holds over a shift of about one grey level's worth of its gradient:
  // where the image is steeper than this knee, residuals weigh less (knee / gradient), so that
  // the step follows the broad shapes that still hold, not the edges that do not. The finest
  // level, where the frame is within a pixel, weighs every residual alike. 0: off. Measured in
  // docs/benchmarks.md (Tracking).
  double coarse_gradient_knee = 7.0;  // grey levels per pixel
  double huber_k = 1.345;             // Huber threshold, in robust standard deviations
  double min_gradient = 3.0;          // finest level: pixels with a weaker intensity gradient only
                                      // take part every second row and column (grey levels/px)

  // A new keyframe after this much motion from the last one, or when too little of it is seen.
  double keyframe_translation = 0.08;  // m
  double keyframe_rotation = 0.20;     // rad
  double keyframe_min_overlap = 0.6;   // fraction of the keyframe's pixels that land in view

  // An estimate is rejected (frame lost, not mapped) when any of these fail.
  double min_overlap = 0.25;           // fraction of keyframe pixels seen in the frame
  double min_depth_fraction = 0.05;    // of the frame's pixels with a usable depth
  double max_residual = 60.0;          // robust std-dev of the intensity residual (grey levels)
  double max_jump_translation = 0.10;  // m from the constant-velocity prediction per frame
  double max_jump_rotation = 0.26;     // rad from the prediction per frame (15 degrees)

  // Relocalisation after a loss: recent keyframes are kept and matched with ORB features.
  int relocalisation_keyframes = 10;
  int relocalisation_min_inliers = 30;  // PnP RANSAC inliers a candidate needs
};

Keys trackingKeys(TrackingOptions& o);

}  // namespace rgbdmap
