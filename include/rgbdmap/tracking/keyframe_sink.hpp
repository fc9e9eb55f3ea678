#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/tracking/readout_motion.hpp"

namespace rgbdmap {

// A tracking keyframe as the tracker made it: what a pose graph needs (its odometry pose and the
// measured motion from the keyframe it was tracked against) and what place recognition needs
// (its images).
struct TrackedKeyframe {
  // In the order made: 0, 1, 2, ..., or from the sink's firstKeyframeId() on.
  std::uint64_t id = 0;
  double timestamp = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // odometry, camera-to-world
  std::int64_t reference = -1;  // the keyframe it was tracked against; -1 for the first
  // Its pose in the reference keyframe's camera, as the aligner measured it, and the information
  // (inverse covariance) of that measurement per aligned pixel, for a perturbation
  // [translation, rotation] applied on the right (in this keyframe's camera).
  Eigen::Isometry3d from_reference = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
  // The camera's motion over its readout (a rolling shutter's; zero for a global one).
  ReadoutMotion readout = ReadoutMotion::Zero();
  cv::Mat color;  // CV_8UC3 BGR, full resolution; the receiver's own (never written again)
  cv::Mat depth;  // CV_32FC1 metres

  // Its images as a frame (shared, not copied): what an image pyramid is built from.
  Frame frame() const {
    Frame out;
    out.color = color;
    out.depth = depth;
    out.timestamp = timestamp;
    return out;
  }
};

// Whoever wants the tracker's keyframes (the loop closer). Called on the tracking thread: an
// implementation must return promptly.
class KeyframeSink {
 public:
  virtual ~KeyframeSink() = default;
  virtual void addKeyframe(TrackedKeyframe keyframe) = 0;
  // The id the tracker's first keyframe takes: above a saved session's keyframes when the sink
  // continues one, so that one id names one keyframe in the graph, the map and the corrections.
  virtual std::uint64_t firstKeyframeId() const { return 0; }
};

}  // namespace rgbdmap
