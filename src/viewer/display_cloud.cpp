#include "rgbdmap/viewer/display_cloud.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdmap {

void DisplayCloud::assign(const MapCloud& map, std::size_t max_points) {
  map_points = map.size();
  const std::size_t stride =
      max_points == 0 ? 1 : std::max<std::size_t>(1, (map.size() + max_points - 1) / max_points);
  points.clear();
  colors.clear();
  points.reserve(map.size() / stride + 1);
  colors.reserve(map.size() / stride + 1);
  for (std::size_t i = 0; i < map.size(); i += stride) {
    const pcl::PointXYZRGB& p = map[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    points.emplace_back(p.x, p.y, p.z);
    colors.push_back({p.r, p.g, p.b});
  }
}

std::vector<Rgb> heightColors(const std::vector<Eigen::Vector3f>& points,
                              const Eigen::Vector3f& up) {
  std::vector<Rgb> colors(points.size());
  if (points.empty()) return colors;
  std::vector<float> heights(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) heights[i] = points[i].dot(up);
  std::vector<float> sorted = heights;
  const auto at = [&](double q) {
    auto nth =
        sorted.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(sorted.size() - 1));
    std::nth_element(sorted.begin(), nth, sorted.end());
    return *nth;
  };
  const float low = at(0.02);
  const float high = at(0.98);
  const float range = std::max(high - low, 1e-6f);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const float t = std::clamp((heights[i] - low) / range, 0.0f, 1.0f);
    // Blue -> cyan -> green -> yellow -> red, in four linear pieces.
    const auto channel = [](float v) {
      return static_cast<std::uint8_t>(std::lround(255.0f * std::clamp(v, 0.0f, 1.0f)));
    };
    colors[i] = {channel(4 * t - 2), channel(std::min(4 * t, 4 - 4 * t)), channel(2 - 4 * t)};
  }
  return colors;
}

}  // namespace rgbdmap
