#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

using Rgb = std::array<std::uint8_t, 3>;

// The part of a map the viewer draws: at most `max_points` of it, every k-th point, so that a
// big map thins out evenly and stays interactive.
struct DisplayCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<Rgb> colors;     // the map's own colours
  std::size_t map_points = 0;  // before decimation

  void assign(const MapCloud& map, std::size_t max_points);
};

// Colours by height along `up`: blue (low) to red (high) over the 2nd..98th percentile of
// heights, so a few stray points do not flatten the ramp.
std::vector<Rgb> heightColors(const std::vector<Eigen::Vector3f>& points,
                              const Eigen::Vector3f& up);

}  // namespace rgbdmap
