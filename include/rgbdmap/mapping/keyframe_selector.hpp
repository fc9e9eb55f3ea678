#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>

#include "rgbdmap/base/option_keys.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"

namespace rgbdmap {

// Which frames become keyframes (config section "keyframe"; see KeyframeSelector).
struct KeyframeOptions {
  std::string policy = "auto";    // auto | interval | motion | both
  int every_n = 10;               // interval: N frames with a pose after the last keyframe
  double min_translation = 0.05;  // motion: metres since the last keyframe
  double min_rotation = 0.0873;   // motion: radians since the last keyframe (5 degrees)
};

Keys keyframeKeys(KeyframeOptions& o);

// Decides which frames are fused into the map. Asking and committing are separate: a keyframe
// that could not be handed to fusion (fusion busy on a live camera) is not committed, so the
// next frame is proposed again instead of the keyframe being lost.
struct KeyframeSelector {
  // kNone: no frame is fused (localisation in a saved map, which stays as it is).
  enum class Policy { kInterval, kMotion, kBoth, kNone };

  KeyframeSelector() : KeyframeSelector(Policy::kInterval, KeyframeOptions{}) {}
  KeyframeSelector(Policy policy, const KeyframeOptions& o)
      : policy(policy),
        every_n(o.every_n),
        min_translation(o.min_translation),
        min_rotation(o.min_rotation) {}

  Policy policy;
  int every_n;
  double min_translation;
  double min_rotation;

  // Called once per frame with a pose. True when this frame should become a keyframe; the first
  // posed frame always is.
  bool wants(const Eigen::Isometry3d& pose) {
    ++frames_since_keyframe_;
    if (policy == Policy::kNone) return false;
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
      case Policy::kNone:
        return false;
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
inline std::string effectiveKeyframePolicy(const KeyframeOptions& keyframe,
                                           const PoseOptions& pose) {
  if (keyframe.policy != "auto") return keyframe.policy;
  return pose.source == "odometry" ? "motion" : "interval";
}

KeyframeSelector makeKeyframeSelector(const KeyframeOptions& keyframe, const PoseOptions& pose);

}  // namespace rgbdmap
