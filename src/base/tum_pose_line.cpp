#include "rgbdmap/base/tum_pose_line.hpp"

#include <cstdio>

namespace rgbdmap {

std::string tumPoseLine(double timestamp, const Eigen::Isometry3d& pose, int quaternion_decimals) {
  const Eigen::Quaterniond q = Eigen::Quaterniond(pose.linear()).normalized();
  const Eigen::Vector3d t = pose.translation();
  const int d = quaternion_decimals;
  const auto print = [&](char* to, std::size_t size) {
    return std::snprintf(to, size, "%.6f %.7f %.7f %.7f %.*f %.*f %.*f %.*f", timestamp, t.x(),
                         t.y(), t.z(), d, q.x(), d, q.y(), d, q.z(), d, q.w());
  };
  std::string line(96, '\0');  // a line of a room-sized trajectory fits
  const std::size_t length = static_cast<std::size_t>(print(line.data(), line.size() + 1));
  if (length > line.size()) {  // far-off coordinates: print again into room for all digits
    line.resize(length);
    print(line.data(), line.size() + 1);
  }
  line.resize(length);
  return line;
}

}  // namespace rgbdmap
