#include "rgbdmap/slam/keyframe_window.hpp"

#include <algorithm>

#include "rgbdmap/slam/motion.hpp"

namespace rgbdmap {

namespace {

TrackingOptions windowOptions(TrackingOptions tracking, const LoopOptions& loop) {
  const int level = loop.window_finest_level;
  if (level < 0) return tracking;  // the tracker's own levels
  if (level >= tracking.finest_level) {
    tracking.finest_level = std::min(level, tracking.coarsest_level);
    return tracking;
  }
  // Finer than the tracker: a pair starts where the graph puts it, which the gate keeps within
  // millimetres, a pixel or so at the tracker's finest level. The coarser levels (large motions)
  // and half the steps are enough there: the same edges on the 30 x 20 m floor, and a lossless
  // replay of it 97 s instead of 115 (docs/benchmarks.md).
  tracking.coarsest_level = tracking.finest_level;
  tracking.finest_level = level;
  tracking.max_iterations = std::max(1, tracking.max_iterations / 2);
  tracking.finest_iterations = std::max(1, tracking.finest_iterations / 2);
  return tracking;
}

}  // namespace

KeyframeWindow::KeyframeWindow(const CameraIntrinsics& camera, const TrackingOptions& tracking,
                               const LoopOptions& loop, double min_depth, double max_depth)
    : camera_(camera),
      tracking_(windowOptions(tracking, loop)),
      options_(loop),
      min_depth_(static_cast<float>(min_depth)),
      max_depth_(static_cast<float>(max_depth)),
      aligner_(tracking_) {}

std::vector<LoopMeasurement> KeyframeWindow::add(
    const TrackedKeyframe& keyframe, const std::function<Eigen::Isometry3d(int)>& pose) {
  std::vector<LoopMeasurement> measured;
  if (options_.window_keyframes <= 0) return measured;
  const int id = static_cast<int>(keyframe.id);
  if (keyframe.color.empty() || keyframe.depth.empty()) {
    entries_.clear();  // nothing to align with: the window starts again after it
    return measured;
  }
  const Frame frame = keyframe.frame();
  pyramid_.build(frame, camera_, tracking_.coarsest_level + 1, tracking_.finest_level,
                 tracking_.undistort, min_depth_, max_depth_);
  const Eigen::Isometry3d later = pose(id);
  aligner_.setReadoutMotion(keyframe.readout);
  for (const Entry& earlier : entries_) {
    if (earlier.id == keyframe.reference) continue;  // the tracker's own edge
    const Eigen::Isometry3d guess = later.inverse() * pose(earlier.id);
    const AlignmentResult result = aligner_.align(earlier.reference, pyramid_, guess);
    if (!result.finite || result.overlap < options_.window_min_overlap ||
        result.intensity_sigma > tracking_.max_residual)
      continue;
    // Odometry over a few keyframes is off by millimetres; an alignment that moves the pair by
    // centimetres found something else (a repeated texture, a wall seen edge-on).
    const Eigen::Isometry3d change = guess.inverse() * result.motion;
    if (change.translation().norm() > options_.window_max_change_translation ||
        rotationAngle(change) > options_.window_max_change_rotation)
      continue;
    LoopMeasurement m = measurementOf(result);
    m.earlier = earlier.id;
    m.later = id;
    measured.push_back(m);
  }
  // The entry that leaves the window lends its buffers to the one that comes in (megabytes that
  // the kernel would otherwise zero again at every keyframe).
  Entry entry;
  while (static_cast<int>(entries_.size()) >= options_.window_keyframes) {
    entry = std::move(entries_.front());
    entries_.pop_front();
  }
  entry.id = id;
  entry.reference.build(pyramid_, tracking_.finest_level, tracking_.coarsest_level,
                        static_cast<float>(tracking_.min_gradient), keyframe.readout);
  entries_.push_back(std::move(entry));
  return measured;
}

}  // namespace rgbdmap
