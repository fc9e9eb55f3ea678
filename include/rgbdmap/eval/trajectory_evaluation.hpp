#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "rgbdmap/capture/trajectory.hpp"

namespace rgbdmap {

// Rigid transform (rotation + translation, no scale) minimising sum |T * from_i - to_i|^2:
// Horn's closed form in its SVD formulation, as align() in TUM's evaluate_ate.py.
// Needs at least 3 pairs, not all on one line, for a unique answer.
Eigen::Isometry3d alignRigid(const std::vector<Eigen::Vector3d>& from,
                             const std::vector<Eigen::Vector3d>& to);

struct ErrorStatistics {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double max = 0.0;
};
ErrorStatistics errorStatistics(std::vector<double> errors);

// Absolute trajectory error as TUM's evaluate_ate.py: estimate and groundtruth stamps associated
// with the 0.02 s rule, estimated positions aligned to groundtruth, position residuals (m).
struct AbsoluteTrajectoryError {
  ErrorStatistics translation;                                  // m, after alignment
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();  // estimate -> groundtruth frame
};
// Throws InputError when fewer than 3 poses associate.
AbsoluteTrajectoryError absoluteTrajectoryError(const Trajectory& estimate,
                                                const Trajectory& groundtruth,
                                                double max_difference = 0.02);

// The rigid transform that moves the estimated cameras' views onto the groundtruth ones, for
// placing a map made from the estimate: each associated pose gives its centre and four points of
// its view (on the optical axis at 1 and 3 m, and at 2 m the left and top edges of a 60 x 45 deg
// view), aligned as alignRigid does. The ATE's alignment of centres alone leaves the tilt of a
// trajectory at one height unobservable (a camera carried level through a floor), and a tilt
// misplaces a map by its angle times the distance from the trajectory's centre: 1.6 cm over 6 m
// at the 0.16 deg a 30 x 20 m floor's position fit was off by.
// Throws InputError when fewer than 3 poses associate.
Eigen::Isometry3d alignViews(const Trajectory& estimate, const Trajectory& groundtruth,
                             double max_difference = 0.02);

// Relative pose error as TUM's evaluate_rpe.py with a fixed interval: for each estimated pose i,
// j is the estimated pose closest to t_i + interval (pairs whose j is the last pose are skipped,
// as the script does); groundtruth poses are the closest stamps, within twice the median
// groundtruth spacing. Error = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j), Q groundtruth, P estimate.
struct RelativePoseError {
  ErrorStatistics translation;  // m
  ErrorStatistics rotation;     // degrees
};
// Throws InputError when no pair can be formed.
RelativePoseError relativePoseError(const Trajectory& estimate, const Trajectory& groundtruth,
                                    double interval = 1.0);

}  // namespace rgbdmap
