#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <optional>

#include "rgbdmap/base/thread_priority.hpp"
#include "rgbdmap/slam/loop_options.hpp"

namespace rgbdmap {

// What loop closure, localisation and merging measure of a camera's motion, one way for all.

constexpr double kDegreesPerRadian = 57.29577951308232;
// A turn counts towards the path walked as this many metres per radian: odometry drifts while
// the camera turns in place too.
constexpr double kMetresPerRadian = 0.3;

inline double rotationAngle(const Eigen::Isometry3d& motion) {
  return Eigen::AngleAxisd(motion.linear()).angle();
}

// A loop may correct a pose by this much (m, and rad) beyond the drift allowance of the path
// walked between its two keyframes (loop.drift_per_metre).
constexpr double kBaseDriftAllowance = 0.05;

// The path a step adds, for the drift allowances that grow with it.
inline double pathLength(const Eigen::Isometry3d& step) {
  return step.translation().norm() + kMetresPerRadian * rotationAngle(step);
}

// Where a run's frame lies in a saved map's, from one of its keyframes (at `own` in the run's
// frame) recognised at a saved keyframe (at `saved`), which sees it at `later_in_earlier`; the
// rotation re-orthonormalised (a product of three poses).
inline Eigen::Isometry3d frameInSavedMap(const Eigen::Isometry3d& saved,
                                         const Eigen::Isometry3d& later_in_earlier,
                                         const Eigen::Isometry3d& own) {
  Eigen::Isometry3d frame = saved * later_in_earlier * own.inverse();
  frame.linear() = Eigen::Quaterniond(frame.linear()).normalized().toRotationMatrix();
  return frame;
}

// Whether two estimates of where one odometry frame lies in a saved map (each from a keyframe
// recognised there) agree: within loop.consistent_*, plus the odometry's drift over the `walked`
// metres between the two keyframes.
inline bool placementsAgree(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double walked,
                            const LoopOptions& loop) {
  const double allowance = loop.drift_per_metre * std::abs(walked);
  const Eigen::Isometry3d change = a.inverse() * b;
  return change.translation().norm() <= loop.consistent_translation + allowance &&
         rotationAngle(change) <= loop.consistent_rotation + allowance;
}

// How far a keyframe at `earlier` is from one at `later`, when it is near enough to be compared
// for a loop: within loop.search_radius and looking within loop.max_view_angle of the same way,
// both grown by `allowance` (the drift the path between them allows). None: too far.
inline std::optional<double> loopSearchDistance(const Eigen::Isometry3d& later,
                                                const Eigen::Isometry3d& earlier, double allowance,
                                                const LoopOptions& loop) {
  const double distance = (earlier.translation() - later.translation()).norm();
  if (distance > loop.search_radius + allowance) return std::nullopt;
  const double cosine = std::clamp(earlier.linear().col(2).dot(later.linear().col(2)), -1.0, 1.0);
  if (std::acos(cosine) > loop.max_view_angle + allowance) return std::nullopt;
  return distance;
}

// The calling thread gives way to tracking and fusion when two cores are short. Loop closure and
// localisation improve what those do; they come first.
inline void giveWayToTracking() { stepBackFromTracking(kLoopNiceness); }

}  // namespace rgbdmap
