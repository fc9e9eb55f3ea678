#pragma once

#include <Eigen/Geometry>
#include <cmath>

namespace rgbdmap {

// exp of a twist (v, w): the rigid motion a Gauss-Newton step on SE(3) stands for (translation
// first, rotation vector last), as the dense aligner and the colour/depth calibrator take steps.
inline Eigen::Isometry3d expSE3(const Eigen::Matrix<double, 6, 1>& xi) {
  const Eigen::Vector3d v = xi.head<3>(), w = xi.tail<3>();
  const double theta = w.norm();
  Eigen::Matrix3d wx;
  wx << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  Eigen::Matrix3d V = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (theta > 1e-10) {
    R = Eigen::AngleAxisd(theta, w / theta).toRotationMatrix();
    V += (1 - std::cos(theta)) / (theta * theta) * wx +
         (theta - std::sin(theta)) / (theta * theta * theta) * wx * wx;
  } else {
    R += wx;
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = V * v;
  return T;
}

}  // namespace rgbdmap
