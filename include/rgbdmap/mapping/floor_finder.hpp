#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// A horizontal plane of the map: the points p with up·p == level.
struct FloorPlane {
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();     // unit, in the map frame
  double level = 0.0;                                // m along up
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // mean of its points
  std::size_t support = 0;                           // map points within inlier_distance of it

  double heightOf(const Eigen::Vector3d& p) const { return up.dot(p) - level; }
};

// Finds the floor in a map without knowing which way is up: the plane with the most surface
// points among those facing roughly the way a guess of up points and lying below every camera.
// Walls and slanted screens are too steep; a table top is smaller than the floor it stands on
// (and is the floor's stand-in when the floor is never seen, as at a desk). RANSAC on a sample
// of the points, then a least-squares fit to all the winner's inliers.
struct FloorFinder {
  struct Config {
    double max_tilt = 0.7;          // rad (40°) between the guess of up and a plane's normal
    double inlier_distance = 0.02;  // m
    double below_cameras = 0.3;     // m: candidates lie this far below the lowest camera
    int iterations = 400;
    std::size_t sample = 30000;  // points RANSAC scores hypotheses on
    std::size_t min_support = 500;
    std::uint32_t seed = 1;
  };

  FloorFinder() = default;
  explicit FloorFinder(const Config& c) : config(c) {}

  // `guess_up` need not be unit; `cameras` are the positions the map was seen from (the floor is
  // below all of them). None when no plane has min_support points.
  std::optional<FloorPlane> find(const MapCloud& map, const Eigen::Vector3d& guess_up,
                                 const std::vector<Eigen::Vector3d>& cameras) const;

  Config config;
};

}  // namespace rgbdmap
