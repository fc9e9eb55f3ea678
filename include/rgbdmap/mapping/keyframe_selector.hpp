#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>

namespace rgbdmap {

// Decides which frames are fused into the map.
struct KeyframeSelector {
  enum class Policy { kInterval, kMotion, kBoth };

  Policy policy = Policy::kInterval;
  int every_n = 10;               // interval: every N-th frame, counting from the first
  double min_translation = 0.05;  // motion: metres since the last keyframe
  double min_rotation = 0.0873;   // motion: radians since the last keyframe

  // `frame_number` counts frames with a pose, from 0. The first such frame is always a keyframe.
  bool isKeyframe(std::uint64_t frame_number, const Eigen::Isometry3d& pose) {
    const bool first = !last_keyframe_pose_.has_value();
    const bool interval_due = frame_number % static_cast<std::uint64_t>(every_n) == 0;
    bool moved = false;
    if (!first) {
      const Eigen::Isometry3d delta = last_keyframe_pose_->inverse() * pose;
      moved = delta.translation().norm() >= min_translation ||
              Eigen::AngleAxisd(delta.linear()).angle() >= min_rotation;
    }
    const bool keyframe = first || (policy == Policy::kInterval && interval_due) ||
                          (policy == Policy::kMotion && moved) ||
                          (policy == Policy::kBoth && (interval_due || moved));
    if (keyframe) last_keyframe_pose_ = pose;
    return keyframe;
  }

 private:
  std::optional<Eigen::Isometry3d> last_keyframe_pose_;
};

}  // namespace rgbdmap
