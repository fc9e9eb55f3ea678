#pragma once

#include <Eigen/Core>
#include <vector>

namespace rgbdmap {

// Points of one depth image in world coordinates, with the pixel each came from.
struct PointBatch {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> colors;  // RGB, 0..255
  std::vector<float> weights;           // inverse measurement variance (relative)
  std::vector<int> pixels;              // row-major pixel index in the depth image

  void clear() {
    positions.clear();
    colors.clear();
    weights.clear();
    pixels.clear();
  }
  std::size_t size() const { return positions.size(); }
};

}  // namespace rgbdmap
