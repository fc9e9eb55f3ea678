#include "rgbdmap/capture/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/text_lines.hpp"
#include "rgbdmap/base/tum_pose_line.hpp"

namespace rgbdmap {

Trajectory Trajectory::load(const std::string& path) {
  Trajectory trajectory;
  for (const TextLine& line : readTextLines(path)) {
    if (line.fields.size() != 8)
      throw InputError(where(path, line.number) +
                       ": expected 8 fields (timestamp tx ty tz qx qy qz qw), found " +
                       std::to_string(line.fields.size()));
    static const char* kNames[] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
    double v[8];
    for (int i = 0; i < 8; ++i) v[i] = parseNumber(line.fields[i], path, line.number, kNames[i]);
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double norm = q.norm();
    // Files carry 4 decimals, so a correct quaternion is unit to about 1e-4.
    if (std::abs(norm - 1.0) > 1e-2)
      throw InputError(where(path, line.number) + ": quaternion norm is " + std::to_string(norm) +
                       ", expected a unit quaternion");
    StampedPose p;
    p.timestamp = v[0];
    p.pose = Eigen::Isometry3d::Identity();
    p.pose.linear() = q.normalized().toRotationMatrix();
    p.pose.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    trajectory.poses_.push_back(p);
  }
  // A continued run's file holds the saved runs' poses first: when the saved run was recorded
  // after this one (a replay of an older sequence) the file is in time order run by run only.
  std::vector<StampedPose>& poses = trajectory.poses_;
  std::stable_sort(poses.begin(), poses.end(), [](const StampedPose& a, const StampedPose& b) {
    return a.timestamp < b.timestamp;
  });
  const auto twice = std::adjacent_find(
      poses.begin(), poses.end(),
      [](const StampedPose& a, const StampedPose& b) { return a.timestamp == b.timestamp; });
  if (twice != poses.end()) {
    char stamp[64];
    std::snprintf(stamp, sizeof stamp, "%.6f", twice->timestamp);
    throw InputError(path + ": timestamp " + stamp + " appears on two lines (one pose a time)");
  }
  return trajectory;
}

void Trajectory::save(const std::string& path) const {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error(tmp + ": cannot open for writing");
    out << kTumPoseHeader;
    for (const StampedPose& p : poses_) out << tumPoseLine(p.timestamp, p.pose) << '\n';
    out.flush();
    if (!out) throw std::runtime_error(tmp + ": write failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot rename temporary file into place");
  }
}

std::optional<Eigen::Isometry3d> Trajectory::interpolate(double t, double max_gap) const {
  if (poses_.empty()) return std::nullopt;
  const auto after =
      std::lower_bound(poses_.begin(), poses_.end(), t,
                       [](const StampedPose& p, double s) { return p.timestamp < s; });
  if (after != poses_.end() && after->timestamp == t) return after->pose;
  if (after == poses_.begin() || after == poses_.end()) return std::nullopt;
  const StampedPose& b = *after;
  const StampedPose& a = *(after - 1);
  if (t - a.timestamp > max_gap || b.timestamp - t > max_gap) return std::nullopt;
  const double s = (t - a.timestamp) / (b.timestamp - a.timestamp);
  const Eigen::Quaterniond qa(a.pose.linear()), qb(b.pose.linear());
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = qa.slerp(s, qb).toRotationMatrix();
  pose.translation() = (1.0 - s) * a.pose.translation() + s * b.pose.translation();
  return pose;
}

std::vector<double> Trajectory::timestamps() const {
  std::vector<double> stamps;
  stamps.reserve(poses_.size());
  for (const StampedPose& p : poses_) stamps.push_back(p.timestamp);
  return stamps;
}

}  // namespace rgbdmap
