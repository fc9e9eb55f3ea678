#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace rgbdmap {

// A TUM accelerometer.txt: "timestamp ax ay az" in m/s², from the Kinect's accelerometer. At
// rest it measures gravity; upAt() turns that into the camera's up direction.
class AccelerometerLog {
 public:
  // Throws InputError naming the file and line that is wrong.
  static AccelerometerLog load(const std::string& path);
  // From samples already read (tests); stamps must increase.
  AccelerometerLog(std::vector<double> stamps, std::vector<Eigen::Vector3d> samples);
  AccelerometerLog() = default;

  bool empty() const { return stamps_.empty(); }
  std::size_t size() const { return stamps_.size(); }

  // The up direction at time t in the camera frame (x right, y down, z forward): the mean of the
  // samples within `window` seconds of t, which averages out the hand's own acceleration; none
  // when no sample is that close or the samples are not about 1 g (the camera was shaken).
  std::optional<Eigen::Vector3d> upAt(double t, double window = 0.05) const;

  // The up direction from one sample (or a mean of samples), none when it is not about 1 g.
  static std::optional<Eigen::Vector3d> upFromSample(const Eigen::Vector3d& sample);

  // The Kinect's accelerometer axes against the camera's: x and y as the optical frame, z
  // reversed, and gravity measured as pointing down. (TUM's fr1 sequences: the ground-truth
  // orientation maps (-ax, -ay, az) onto the motion-capture frame's up within 5 degrees.)
  static Eigen::Vector3d upInCamera(const Eigen::Vector3d& sample) {
    return Eigen::Vector3d(-sample.x(), -sample.y(), sample.z());
  }

 private:
  std::vector<double> stamps_;
  std::vector<Eigen::Vector3d> samples_;
};

}  // namespace rgbdmap
