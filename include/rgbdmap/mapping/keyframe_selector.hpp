#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>

#include "rgbdmap/base/config.hpp"

namespace rgbdmap {

// Decides which frames are fused into the map. Asking and committing are separate: a keyframe
// that could not be handed to fusion (fusion busy on a live camera) is not committed, so the
// next frame is proposed again instead of the keyframe being lost.
struct KeyframeSelector {
  enum class Policy { kInterval, kMotion, kBoth };

  Policy policy = Policy::kInterval;
  int every_n = 10;               // interval: N frames with a pose after the last keyframe
  double min_translation = 0.05;  // motion: metres since the last keyframe
  double min_rotation = 0.0873;   // motion: radians since the last keyframe

  // Called once per frame with a pose. True when this frame should become a keyframe; the first
  // posed frame always is.
  bool wants(const Eigen::Isometry3d& pose) {
    ++frames_since_keyframe_;
    if (!last_keyframe_pose_) return true;
    const bool interval_due = frames_since_keyframe_ >= static_cast<std::uint64_t>(every_n);
    const Eigen::Isometry3d delta = last_keyframe_pose_->inverse() * pose;
    const bool moved = delta.translation().norm() >= min_translation ||
                       Eigen::AngleAxisd(delta.linear()).angle() >= min_rotation;
    switch (policy) {
      case Policy::kInterval:
        return interval_due;
      case Policy::kMotion:
        return moved;
      case Policy::kBoth:
        return interval_due || moved;
    }
    return false;
  }
  // The frame wants() proposed is now a keyframe.
  void accept(const Eigen::Isometry3d& pose) {
    last_keyframe_pose_ = pose;
    frames_since_keyframe_ = 0;
  }

 private:
  std::optional<Eigen::Isometry3d> last_keyframe_pose_;
  std::uint64_t frames_since_keyframe_ = 0;
};

// keyframe.policy with "auto" resolved: motion when poses come from tracking (live cameras,
// recordings, folders without ground truth), interval otherwise. A tracked camera held still
// should add nothing (each fused view of the same place also fuses the tracker's small errors),
// and a fast one should add keyframes as fast as it uncovers new surfaces; with ground truth or a
// trajectory file every N-th frame reproduces the original method and fixed fused-frame counts.
inline std::string effectiveKeyframePolicy(const Config& config) {
  if (config.keyframe_policy != "auto") return config.keyframe_policy;
  return config.pose_source == "odometry" ? "motion" : "interval";
}

KeyframeSelector makeKeyframeSelector(const Config& config);

}  // namespace rgbdmap
