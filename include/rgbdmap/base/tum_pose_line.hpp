#pragma once

#include <Eigen/Geometry>
#include <string>

namespace rgbdmap {

// The comment line that heads a TUM trajectory file, newline included.
constexpr char kTumPoseHeader[] = "# timestamp tx ty tz qx qy qz qw\n";

// One line of a TUM trajectory file, "timestamp tx ty tz qx qy qz qw" (quaternion scalar-last,
// normalised), without the newline: the one writer of every trajectory the project saves. The
// timestamp has 6 decimals (microseconds), the translation 7 (0.1 um), the quaternion
// `quaternion_decimals` (7 for estimates; the ground truth the simulator writes keeps 9).
std::string tumPoseLine(double timestamp, const Eigen::Isometry3d& pose,
                        int quaternion_decimals = 7);

}  // namespace rgbdmap
