#include "rgbdmap/capture/accelerometer_log.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/text_lines.hpp"

namespace rgbdmap {
namespace {

constexpr double kGravity = 9.81;  // m/s²
// A mean this far from 1 g is the hand's acceleration more than gravity: no direction from it.
constexpr double kMaxDeviation = 0.25 * kGravity;

}  // namespace

AccelerometerLog AccelerometerLog::load(const std::string& path) {
  std::vector<double> stamps;
  std::vector<Eigen::Vector3d> samples;
  for (const TextLine& line : readTextLines(path)) {
    if (line.fields.size() != 4)
      throw InputError(where(path, line.number) +
                       ": expected 4 fields (timestamp ax ay az), found " +
                       std::to_string(line.fields.size()));
    const double t = parseNumber(line.fields[0], path, line.number, "timestamp");
    Eigen::Vector3d a;
    static const char* kNames[] = {"ax", "ay", "az"};
    for (int i = 0; i < 3; ++i)
      a[i] = parseNumber(line.fields[i + 1], path, line.number, kNames[i]);
    if (!stamps.empty() && t <= stamps.back())
      throw InputError(where(path, line.number) + ": timestamp " + line.fields[0] +
                       " is not after the previous line's");
    stamps.push_back(t);
    samples.push_back(a);
  }
  return AccelerometerLog(std::move(stamps), std::move(samples));
}

AccelerometerLog::AccelerometerLog(std::vector<double> stamps, std::vector<Eigen::Vector3d> samples)
    : stamps_(std::move(stamps)), samples_(std::move(samples)) {}

std::optional<Eigen::Vector3d> AccelerometerLog::upAt(double t, double window) const {
  auto it = std::lower_bound(stamps_.begin(), stamps_.end(), t - window);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (; it != stamps_.end() && *it <= t + window; ++it, ++n)
    sum += samples_[static_cast<std::size_t>(it - stamps_.begin())];
  if (n == 0) return std::nullopt;
  return upFromSample(sum / n);
}

std::optional<Eigen::Vector3d> AccelerometerLog::upFromSample(const Eigen::Vector3d& sample) {
  if (std::abs(sample.norm() - kGravity) > kMaxDeviation) return std::nullopt;
  return upInCamera(sample).normalized();
}

}  // namespace rgbdmap
