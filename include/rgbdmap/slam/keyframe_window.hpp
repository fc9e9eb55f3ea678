#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <functional>
#include <vector>

#include "rgbdmap/slam/loop_options.hpp"
#include "rgbdmap/slam/place_recognition.hpp"
#include "rgbdmap/tracking/dense_aligner.hpp"
#include "rgbdmap/tracking/image_pyramid.hpp"
#include "rgbdmap/tracking/keyframe_sink.hpp"
#include "rgbdmap/tracking/tracking_options.hpp"

namespace rgbdmap {

// Ties each new keyframe to the few keyframes before it, not only to the one it was tracked
// against (DVO-SLAM's keyframe graph): a keyframe's odometry error is its own, and a second and
// third alignment to the keyframes around it averages it out once the graph weighs them all.
// Each is a dense alignment, with the tracker's settings, of an earlier keyframe's pixels into
// the new one, started from where the graph puts the two; it counts only when it passes the
// tracker's checks and moves the pair less than a wrong alignment would (loop.window_*).
class KeyframeWindow {
 public:
  KeyframeWindow(const CameraIntrinsics& camera, const TrackingOptions& tracking,
                 const LoopOptions& loop, double min_depth, double max_depth);

  // Aligns the window's keyframes other than `keyframe.reference` to `keyframe` (its images), with
  // `pose` the graph's estimate of a keyframe by id; then takes it into the window. Measurements
  // as loops are (later = keyframe.id; ids, later_in_earlier, information, overlap).
  std::vector<LoopMeasurement> add(const TrackedKeyframe& keyframe,
                                   const std::function<Eigen::Isometry3d(int)>& pose);

 private:
  struct Entry {
    int id = 0;
    AlignmentReference reference;
  };
  CameraIntrinsics camera_;
  TrackingOptions tracking_;
  LoopOptions options_;
  float min_depth_, max_depth_;
  DenseAligner aligner_;
  ImagePyramid pyramid_;
  std::deque<Entry> entries_;  // newest last
};

}  // namespace rgbdmap
