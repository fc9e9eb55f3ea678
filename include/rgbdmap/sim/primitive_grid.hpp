#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace rgbdmap {

// A uniform grid over the ground plane (world x, y; z is up) listing, for each square cell, the
// primitives whose footprint (their x-y bounding rectangle) overlaps it. A building's floor holds
// hundreds of walls and pieces of furniture, but a ray only passes over a few cells before it
// hits something: walking the cells along the ray and testing only what they list keeps
// rendering as fast as in one room. Primitives that span the whole scene (the room's shell) are
// not listed; the scene tests them for every ray.
class PrimitiveGrid {
 public:
  // Footprints as (min x, min y, max x, max y), one per primitive; NaN rows are left out.
  void build(const std::vector<Eigen::Vector4d>& footprints, double cell_size);
  bool empty() const { return offsets_.empty(); }
  double cellSize() const { return cell_; }

  // Calls visit(first, last, t_exit) for each cell the ground projection of o + t d (t >= 0)
  // crosses, nearest first: [first, last) are the indices listed in the cell and t_exit is where
  // the ray leaves it. Stops when visit returns false or the ray leaves the grid.
  template <typename Visit>
  void walkRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d, Visit&& visit) const;

  // Calls visit(first, last) for every cell at Chebyshev distance `ring` from the cell of (x, y),
  // and returns how far (x, y) is from every cell not yet visited (rings 0..ring): a lower bound
  // on the ground distance to any primitive listed only outside them. -1 when (x, y) is outside
  // the grid or no cell of the ring lies in it (all done).
  template <typename Visit>
  double visitRing(double x, double y, int ring, Visit&& visit) const;

  // The indices listed in the cell holding (x, y); empty outside the grid.
  template <typename Visit>
  void visitCellAt(double x, double y, Visit&& visit) const;

 private:
  const std::uint32_t* cellBegin(int i, int j) const {
    return items_.data() + offsets_[index(i, j)];
  }
  const std::uint32_t* cellEnd(int i, int j) const {
    return items_.data() + offsets_[index(i, j) + 1];
  }
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) +
           static_cast<std::size_t>(i);
  }
  bool cellOf(double x, double y, int& i, int& j) const {
    const double fx = (x - x0_) / cell_, fy = (y - y0_) / cell_;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < nx_ && fy < ny_)) return false;
    i = static_cast<int>(fx);
    j = static_cast<int>(fy);
    return true;
  }

  double x0_ = 0.0, y0_ = 0.0, cell_ = 1.0;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> offsets_;  // per cell, into items_ (compressed rows)
  std::vector<std::uint32_t> items_;
};

template <typename Visit>
void PrimitiveGrid::walkRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                            Visit&& visit) const {
  if (empty() || !o.allFinite() || !d.allFinite()) return;
  // Clip the ray's ground projection to the grid's rectangle.
  const double lo[2] = {x0_, y0_};
  const double hi[2] = {x0_ + nx_ * cell_, y0_ + ny_ * cell_};
  double t_in = 0.0, t_out = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0.0) {
      if (o[k] < lo[k] || o[k] >= hi[k]) return;
      continue;
    }
    double t1 = (lo[k] - o[k]) / d[k], t2 = (hi[k] - o[k]) / d[k];
    if (t1 > t2) std::swap(t1, t2);
    t_in = std::max(t_in, t1);
    t_out = std::min(t_out, t2);
  }
  if (t_in > t_out) return;
  // The cell where the ray enters (or starts), clamped against rounding at the border.
  const double ex = o.x() + t_in * d.x(), ey = o.y() + t_in * d.y();
  int i = std::clamp(static_cast<int>(std::floor((ex - x0_) / cell_)), 0, nx_ - 1);
  int j = std::clamp(static_cast<int>(std::floor((ey - y0_) / cell_)), 0, ny_ - 1);
  // Classic 2-D DDA (Amanatides and Woo): the ray parameter of the next x and y cell borders.
  const int step_i = d.x() > 0.0 ? 1 : -1, step_j = d.y() > 0.0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  const double delta_x = d.x() != 0.0 ? cell_ / std::abs(d.x()) : inf;
  const double delta_y = d.y() != 0.0 ? cell_ / std::abs(d.y()) : inf;
  double next_x = inf, next_y = inf;
  if (d.x() != 0.0) next_x = (x0_ + (i + (step_i > 0 ? 1 : 0)) * cell_ - o.x()) / d.x();
  if (d.y() != 0.0) next_y = (y0_ + (j + (step_j > 0 ? 1 : 0)) * cell_ - o.y()) / d.y();
  for (;;) {
    const double t_exit = std::min({next_x, next_y, t_out});
    if (!visit(cellBegin(i, j), cellEnd(i, j), t_exit)) return;
    if (t_exit >= t_out) return;
    if (next_x < next_y) {
      i += step_i;
      next_x += delta_x;
    } else {
      j += step_j;
      next_y += delta_y;
    }
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return;
  }
}

template <typename Visit>
double PrimitiveGrid::visitRing(double x, double y, int ring, Visit&& visit) const {
  int ci = 0, cj = 0;
  if (empty() || !cellOf(x, y, ci, cj)) return -1.0;
  const int i0 = ci - ring, i1 = ci + ring, j0 = cj - ring, j1 = cj + ring;
  if (i0 < 0 && j0 < 0 && i1 >= nx_ && j1 >= ny_) return -1.0;
  for (int j = std::max(j0, 0); j <= std::min(j1, ny_ - 1); ++j) {
    const bool edge_row = j == j0 || j == j1;
    for (int i = std::max(i0, 0); i <= std::min(i1, nx_ - 1); ++i) {
      if (!edge_row && i != i0 && i != i1) continue;
      visit(cellBegin(i, j), cellEnd(i, j));
    }
  }
  // Distance from (x, y) to the outside of the block of cells visited so far.
  const double left = x - (x0_ + i0 * cell_), right = x0_ + (i1 + 1) * cell_ - x;
  const double below = y - (y0_ + j0 * cell_), above = y0_ + (j1 + 1) * cell_ - y;
  return std::min({left, right, below, above});
}

template <typename Visit>
void PrimitiveGrid::visitCellAt(double x, double y, Visit&& visit) const {
  int i = 0, j = 0;
  if (empty() || !cellOf(x, y, i, j)) return;
  visit(cellBegin(i, j), cellEnd(i, j));
}

}  // namespace rgbdmap
