#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "rgbdmap/base/option_keys.hpp"
#include "rgbdmap/mapping/floor_finder.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// Which way is up and where the floor is (config section "up"), when not found by themselves.
struct UpOptions {
  std::string vector = "auto";        // "auto", or "x,y,z": up in the map frame
  std::string floor_height = "auto";  // "auto", or metres: up·p of the floor's points
};

Keys upKeys(UpOptions& o);

// What is known about up from the run: accelerometer readings and the cameras' own axes, each
// turned into the map frame with the keyframe's pose, and where the keyframes were.
struct UpEvidence {
  Eigen::Vector3d accelerometer_up = Eigen::Vector3d::Zero();  // sum of unit vectors
  int accelerometer_keyframes = 0;
  Eigen::Vector3d camera_up = Eigen::Vector3d::Zero();  // sum of the cameras' -y axes
  std::vector<Eigen::Vector3d> cameras;                 // keyframe positions
};

// The floor's frame in the map frame: z is up, z = 0 on the floor, x along the map's x (or z when
// that is vertical). Grids are drawn in its xy plane.
struct GroundFrame {
  enum class UpSource { kConfigured, kAccelerometer, kFloor, kCameras };
  enum class FloorSource { kConfigured, kPlane, kLowestSurface };

  Eigen::Isometry3d map_from_ground = Eigen::Isometry3d::Identity();
  UpSource up_source = UpSource::kCameras;
  // What chose the floor among level planes (configured, accelerometer or cameras), and the angle
  // between it and the up used (rad): how far the accelerometer and the floor disagree.
  UpSource guess_source = UpSource::kCameras;
  double angle_to_guess = 0.0;
  FloorSource floor_source = FloorSource::kLowestSurface;
  std::optional<FloorPlane> floor;  // the plane found, if one was

  Eigen::Vector3d up() const { return map_from_ground.linear().col(2); }
  // "up from the floor plane (0.012, -0.998, 0.061), 0.8° from the accelerometer's; floor plane
  // at -1.234 m (48211 points)".
  std::string describe() const;
  // Where up and the floor came from, without the numbers: what a log compares to say it again
  // only when it changes.
  std::string sources() const {
    return std::to_string(static_cast<int>(up_source)) + "/" +
           std::to_string(static_cast<int>(guess_source)) + "/" +
           std::to_string(static_cast<int>(floor_source));
  }

  // The floor is the largest level plane below the cameras, level as the best guess of up says:
  // configured, else the accelerometer's, else the cameras' -y axes. Up is then the configured
  // one, else the floor's normal (the grid's cells must lie in the map's floor, even where
  // tracking tilted it a little against gravity), else the guess. The floor's height is
  // configured, else the plane's, else the lowest surfaces'. Throws std::invalid_argument when a
  // configured value does not parse.
  // Throws std::invalid_argument when a configured value does not parse.
  static GroundFrame resolve(const MapCloud& map, const UpEvidence& evidence,
                             const UpOptions& options, const FloorFinder& finder = FloorFinder{});
};

}  // namespace rgbdmap
