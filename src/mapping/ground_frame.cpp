#include "rgbdmap/mapping/ground_frame.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rgbdmap {
namespace {

// The lowest surfaces stand in for the floor when no plane is found: the 1st percentile of the
// points' heights, so that a few points below the floor (noise, a reflection) do not decide it.
constexpr double kLowestSurfaceQuantile = 0.01;

std::optional<Eigen::Vector3d> parseVector(const std::string& text) {
  if (text == "auto") return std::nullopt;
  std::string spaced = text;
  std::replace(spaced.begin(), spaced.end(), ',', ' ');
  std::istringstream in(spaced);
  Eigen::Vector3d v;
  if (!(in >> v.x() >> v.y() >> v.z()) || !(in >> std::ws).eof() || !v.allFinite() ||
      v.norm() < 1e-9)
    throw std::invalid_argument("up.vector must be auto or three numbers x,y,z, not '" + text +
                                "'");
  return v.normalized();
}

std::optional<double> parseHeight(const std::string& text) {
  if (text == "auto") return std::nullopt;
  double value = 0.0;
  if (!parseFiniteNumber(text, value))
    throw std::invalid_argument("up.floor_height must be auto or metres, not '" + text + "'");
  return value;
}

double lowestSurface(const MapCloud& map, const Eigen::Vector3d& up) {
  if (map.empty()) return 0.0;
  std::vector<double> heights;
  heights.reserve(map.size());
  for (const auto& p : map.points) heights.push_back(up.dot(Eigen::Vector3d(p.x, p.y, p.z)));
  const auto nth =
      heights.begin() +
      static_cast<std::ptrdiff_t>(kLowestSurfaceQuantile * static_cast<double>(heights.size()));
  std::nth_element(heights.begin(), nth, heights.end());
  return *nth;
}

}  // namespace

Keys upKeys(UpOptions& o) {
  Keys keys = {
      text("up.vector", &o.vector,
           "which way is up in the map frame: auto (the accelerometer, else the floor) or x,y,z"),
      text("up.floor_height", &o.floor_height,
           "where the floor is: auto (the largest level plane below the cameras) or metres along "
           "up from the map's origin"),
  };
  keys[0] = checked(std::move(keys[0]), [&o] { parseVector(o.vector); });
  keys[1] = checked(std::move(keys[1]), [&o] { parseHeight(o.floor_height); });
  return keys;
}

std::string GroundFrame::describe() const {
  static const char* kSource[] = {"configured", "the accelerometer", "the floor plane",
                                  "the cameras"};
  const Eigen::Vector3d u = up();
  std::string text = fmt::format("up from {} ({:.3f}, {:.3f}, {:.3f})",
                                 kSource[static_cast<int>(up_source)], u.x(), u.y(), u.z());
  if (up_source != guess_source)
    text += fmt::format(", {:.1f} degrees from {}", angle_to_guess * 180.0 / M_PI,
                        kSource[static_cast<int>(guess_source)]);
  const double level = u.dot(map_from_ground.translation());
  switch (floor_source) {
    case FloorSource::kConfigured:
      return text + fmt::format("; floor configured at {:.3f} m", level);
    case FloorSource::kPlane:
      return text + fmt::format("; floor plane at {:.3f} m ({} points)", level, floor->support);
    case FloorSource::kLowestSurface:
      break;
  }
  return text +
         fmt::format("; no floor plane found, floor at the lowest surfaces ({:.3f} m)", level);
}

GroundFrame GroundFrame::resolve(const MapCloud& map, const UpEvidence& evidence,
                                 const UpOptions& options, const FloorFinder& finder) {
  GroundFrame frame;
  const std::optional<Eigen::Vector3d> configured_up = parseVector(options.vector);
  const std::optional<double> configured_floor = parseHeight(options.floor_height);

  Eigen::Vector3d guess = evidence.camera_up.norm() > 1e-9 ? evidence.camera_up.normalized()
                                                           : Eigen::Vector3d(0, -1, 0);
  frame.guess_source = UpSource::kCameras;
  if (evidence.accelerometer_keyframes > 0 && evidence.accelerometer_up.norm() > 1e-9) {
    guess = evidence.accelerometer_up.normalized();
    frame.guess_source = UpSource::kAccelerometer;
  }
  if (configured_up) {
    guess = *configured_up;
    frame.guess_source = UpSource::kConfigured;
  }
  frame.floor = finder.find(map, guess, evidence.cameras);
  Eigen::Vector3d up = guess;
  frame.up_source = frame.guess_source;
  if (frame.floor && !configured_up) {
    up = frame.floor->up;
    frame.up_source = UpSource::kFloor;
  }
  frame.angle_to_guess = std::acos(std::clamp(up.dot(guess), -1.0, 1.0));

  double level = 0.0;
  if (configured_floor) {
    level = *configured_floor;
    frame.floor_source = FloorSource::kConfigured;
  } else if (frame.floor) {
    level = up.dot(frame.floor->centre);
    frame.floor_source = FloorSource::kPlane;
  } else {
    level = lowestSurface(map, up);
    frame.floor_source = FloorSource::kLowestSurface;
  }

  Eigen::Vector3d x = Eigen::Vector3d::UnitX() - up * up.x();
  if (x.norm() < 0.1) x = Eigen::Vector3d::UnitZ() - up * up.z();
  x.normalize();
  Eigen::Matrix3d axes;
  axes.col(0) = x;
  axes.col(1) = up.cross(x);
  axes.col(2) = up;
  frame.map_from_ground.linear() = axes;
  frame.map_from_ground.translation() = up * level;
  return frame;
}

}  // namespace rgbdmap
