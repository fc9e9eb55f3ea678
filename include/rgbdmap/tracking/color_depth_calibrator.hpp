#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap {

class WorkerPool;

// One capture as the calibrator needs it: the colour camera's grey image (CV_32FC1, 0..255, an
// ideal pinhole view) and the depth camera's own depth (CV_32FC1, metres, 0 = none).
struct CalibrationFrame {
  cv::Mat gray;
  cv::Mat depth;
};

// What the calibration estimates: the colour camera's focal lengths or the depth camera's
// (scaled together, their declared ratio kept; the principal points stay the declared ones: a
// shift of one and a small turn of the depth camera look the same) and the depth camera's pose
// in the colour camera's frame.
struct ColorDepthCalibration {
  double fx = 525.0, fy = 525.0;
  // The depth camera's focal lengths over those it was given (ColorDepthCalibrator::Config::
  // estimate_depth_focal; else 1).
  double depth_focal_scale = 1.0;
  Eigen::Isometry3d color_from_depth = Eigen::Isometry3d::Identity();
};

struct CalibrationReport {
  ColorDepthCalibration calibration;
  // Edge points whose colour edge was found, and their RMS distance to it along the edge's
  // normal (px, full resolution): at the guess and at the estimate.
  std::size_t edges_before = 0, edges_after = 0;
  double rms_before = 0.0, rms_after = 0.0;
  // How well the captures determine the estimate: standard deviations of the depth camera's
  // position (m) and rotation (rad), and of the focal length estimated (a fraction of it).
  double translation_sd = 0.0, rotation_sd = 0.0, focal_sd = 0.0;
};

// Finds the colour camera's focal length and the depth camera's pose in it from captures of
// any scene with objects in front of others. Where depth jumps (an object's outline), the colour
// changes too: each outline point of the depth image, moved into the colour camera, must land
// on the colour edge beside it. Each step looks for that edge along the outline's normal (the
// strongest intensity change within a few pixels) and moves the calibration to close the gaps,
// by Gauss-Newton with Huber weights, the search narrowing, like ICP on edges. Why
// outlines rather than the consistency of two captures' colour: docs/cameras.md.
class ColorDepthCalibrator {
 public:
  struct Config {
    int iterations = 15;        // Gauss-Newton steps per search range, at most
    double search_px = 8.0;     // how far along the normal to look for the colour edge (px)
                                // at first; halved down to 2 as the estimate closes in
    double min_gradient = 4.0;  // a colour edge changes by at least this (grey levels/px)
    double unique = 0.7;        // and no other in the range by more than this share of it
    double min_jump = 0.05;     // depth jumps by this (m) plus 5% to make an outline
    double min_depth = 0.4;     // m
    double max_depth = 4.0;     // m
    int max_edges_per_frame = 4000;
    // Starts tried beside the guess: the depth camera moved across the view by up to this (half
    // of it up and down), in steps of start_step_m.
    double start_offset_m = 0.03;
    double start_step_m = 0.005;
    // Whether the depth camera's offset along the view is estimated or kept at the guess's: on
    // real recordings the outlines trade it against the focal length (docs/cameras.md).
    bool estimate_depth_z = true;
    // Which focal length is estimated: the colour camera's (false: the depth camera's
    // intrinsics are known, e.g. a dataset's) or the depth camera's (true: its intrinsics are
    // not known and the colour camera's are). The outlines tell only their ratio apart from
    // the baseline, so one of them is kept. The depth camera's guess (the colour camera's) may
    // then be 10% off, as a Kinect's 580 px are from 525: starts are tried across that range.
    bool estimate_depth_focal = false;
    double start_focal_range = 0.15;  // +- this share of the guess, in steps of start_focal_step
    double start_focal_step = 0.025;
  };

  // `color`: the colour camera's declared intrinsics (its principal point is kept); `depth`:
  // the depth camera's, taken as exact (with the lens distortion its depth image has, if any).
  ColorDepthCalibrator(const Config& config, const CameraIntrinsics& color,
                       const CameraIntrinsics& depth);

  // Throws std::runtime_error when the captures show too few outlines to estimate anything.
  CalibrationReport estimate(const std::vector<CalibrationFrame>& frames,
                             const ColorDepthCalibration& guess, WorkerPool& pool) const;

 private:
  Config config_;
  CameraIntrinsics color_, depth_;
};

}  // namespace rgbdmap
