#include "rgbdmap/tracking/tracking_options.hpp"

namespace rgbdmap {

Keys trackingKeys(TrackingOptions& o) {
  return {
      choice("tracking.method", &o.method, {"dense", "opencv_rgbd", "opencv_rgbd_icp"},
             "odometry: dense (ours, against keyframes), opencv_rgbd or opencv_rgbd_icp (OpenCV)"),
      integer("tracking.coarsest_level", &o.coarsest_level, 1, 6,
              "dense: coarsest pyramid level aligned (each level halves the image)"),
      integer("tracking.finest_level", &o.finest_level, 0, 6,
              "dense: finest pyramid level aligned (0 = full resolution, 1 = 320x240)"),
      integer("tracking.max_iterations", &o.max_iterations, 1, 100,
              "dense: Gauss-Newton steps per coarse level"),
      integer("tracking.finest_iterations", &o.finest_iterations, 1, 100,
              "dense: Gauss-Newton steps on the finest level"),
      boolean("tracking.estimate_readout", &o.estimate_readout,
              "dense: measure the rolling shutter's readout while tracking, from camera.readout"),
      number("tracking.readout_prior_weight", &o.readout_prior_weight, 0, 1e12,
             "dense: how much camera.readout counts against the readout alignments measure "
             "(their readout information, 1/s^2)"),
      number("tracking.depth_weight", &o.depth_weight, 0, 100,
             "dense: weight of depth residuals against intensity residuals (0 = photometric only)"),
      choice("tracking.depth_noise", &o.depth_noise, {"quadratic", "constant"},
             "dense: a depth residual's noise grows with depth squared (quadratic: structured "
             "light, stereo) or is the same everywhere (constant)"),
      choice(
          "tracking.brightness", &o.brightness, {"offset", "none"},
          "dense: offset: estimate how much brighter a frame is than its reference "
          "(auto-exposure) and take it out of the intensity residuals; none: compare as they are"),
      number("tracking.brightness_tolerance", &o.brightness_tolerance, 0, 255,
             "dense: a brightness offset is taken out less this much (grey levels): smaller "
             "ones are as likely a misalignment"),
      number("tracking.coarse_gradient_knee", &o.coarse_gradient_knee, 0, 255,
             "dense: on the coarse levels, intensity residuals where the image is steeper than "
             "this (grey/px) weigh less (knee/gradient); 0 = every residual alike"),
      number("tracking.huber_k", &o.huber_k, 0.1, 100,
             "dense: Huber threshold in robust standard deviations"),
      number("tracking.min_gradient", &o.min_gradient, 0, 255,
             "dense: finest-level pixels with a weaker gradient (grey/px) are thinned to 1 in 4"),
      number("tracking.keyframe_translation", &o.keyframe_translation, 0, 10,
             "dense: a new tracking keyframe after moving this far (m)"),
      number("tracking.keyframe_rotation", &o.keyframe_rotation, 0, 3.15,
             "dense: a new tracking keyframe after turning this far (rad)"),
      number("tracking.keyframe_min_overlap", &o.keyframe_min_overlap, 0, 1,
             "dense: a new tracking keyframe when less of the last one is in view"),
      number("tracking.min_overlap", &o.min_overlap, 0, 1,
             "a frame is lost when less of the keyframe's pixels land in it"),
      number("tracking.min_depth_fraction", &o.min_depth_fraction, 0, 1,
             "a frame is lost (not mapped) when fewer of its pixels have depth"),
      number("tracking.max_residual", &o.max_residual, 0.1, 255,
             "a frame is lost when the intensity residual's robust std-dev exceeds this (grey)"),
      number("tracking.max_jump_translation", &o.max_jump_translation, 0.001, 10,
             "a frame is lost when it lands this far (m per frame period) from the prediction"),
      number("tracking.max_jump_rotation", &o.max_jump_rotation, 0.001, 3.15,
             "a frame is lost when it turns this far (rad per frame period) from the prediction"),
      integer("tracking.relocalisation_keyframes", &o.relocalisation_keyframes, 1, 1000,
              "recent keyframes kept to relocalise against after a loss"),
      integer("tracking.relocalisation_min_inliers", &o.relocalisation_min_inliers, 6, 10000,
              "ORB + PnP RANSAC inliers a relocalisation needs"),
  };
}

}  // namespace rgbdmap
