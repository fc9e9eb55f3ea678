#include "rgbdmap/sim/primitive_grid.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdmap {

void PrimitiveGrid::build(const std::vector<Eigen::Vector4d>& footprints, double cell_size) {
  offsets_.clear();
  items_.clear();
  cell_ = cell_size;
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  for (const Eigen::Vector4d& f : footprints) {
    if (!f.allFinite()) continue;
    min_x = std::min(min_x, f[0]);
    min_y = std::min(min_y, f[1]);
    max_x = std::max(max_x, f[2]);
    max_y = std::max(max_y, f[3]);
  }
  if (!(min_x <= max_x && min_y <= max_y)) return;
  x0_ = min_x;
  y0_ = min_y;
  nx_ = static_cast<int>(std::floor((max_x - min_x) / cell_)) + 1;
  ny_ = static_cast<int>(std::floor((max_y - min_y) / cell_)) + 1;
  // Two passes: count per cell, then fill (compressed rows: one allocation however many cells).
  auto range = [&](const Eigen::Vector4d& f, int& i0, int& j0, int& i1, int& j1) {
    i0 = std::clamp(static_cast<int>(std::floor((f[0] - x0_) / cell_)), 0, nx_ - 1);
    j0 = std::clamp(static_cast<int>(std::floor((f[1] - y0_) / cell_)), 0, ny_ - 1);
    i1 = std::clamp(static_cast<int>(std::floor((f[2] - x0_) / cell_)), 0, nx_ - 1);
    j1 = std::clamp(static_cast<int>(std::floor((f[3] - y0_) / cell_)), 0, ny_ - 1);
  };
  std::vector<std::uint32_t> counts(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
  for (const Eigen::Vector4d& f : footprints) {
    if (!f.allFinite()) continue;
    int i0, j0, i1, j1;
    range(f, i0, j0, i1, j1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) ++counts[index(i, j) + 1];
  }
  for (std::size_t k = 1; k < counts.size(); ++k) counts[k] += counts[k - 1];
  offsets_ = counts;
  items_.resize(offsets_.back());
  for (std::size_t n = 0; n < footprints.size(); ++n) {
    const Eigen::Vector4d& f = footprints[n];
    if (!f.allFinite()) continue;
    int i0, j0, i1, j1;
    range(f, i0, j0, i1, j1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) items_[counts[index(i, j)]++] = static_cast<std::uint32_t>(n);
  }
}

}  // namespace rgbdmap
