#include "rgbdmap/mapping/floor_finder.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace rgbdmap {
namespace {

// The least-squares plane through points (the smallest principal axis), its normal turned
// towards `up`.
FloorPlane fitPlane(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& up) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) covariance += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  Eigen::Vector3d normal = solver.eigenvectors().col(0);  // eigenvalues ascending
  if (normal.dot(up) < 0.0) normal = -normal;
  FloorPlane plane;
  plane.up = normal;
  plane.level = normal.dot(mean);
  plane.centre = mean;
  plane.support = points.size();
  return plane;
}

}  // namespace

std::optional<FloorPlane> FloorFinder::find(const MapCloud& map, const Eigen::Vector3d& guess_up,
                                            const std::vector<Eigen::Vector3d>& cameras) const {
  if (guess_up.norm() < 1e-9) return std::nullopt;
  const Eigen::Vector3d up = guess_up.normalized();
  double lowest_camera = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& c : cameras) lowest_camera = std::min(lowest_camera, up.dot(c));
  const double ceiling = lowest_camera - config.below_cameras;

  std::vector<Eigen::Vector3d> candidates;
  for (const auto& p : map.points) {
    const Eigen::Vector3d q(p.x, p.y, p.z);
    if (up.dot(q) < ceiling) candidates.push_back(q);
  }
  if (candidates.size() < config.min_support) return std::nullopt;

  std::mt19937 rng(config.seed);
  std::vector<Eigen::Vector3d> sample = candidates;
  if (sample.size() > config.sample) {
    std::shuffle(sample.begin(), sample.end(), rng);
    sample.resize(config.sample);
  }
  std::uniform_int_distribution<std::size_t> pick(0, sample.size() - 1);
  const double min_cosine = std::cos(config.max_tilt);
  Eigen::Vector3d best_normal = Eigen::Vector3d::Zero();
  double best_level = 0.0;
  std::size_t best_count = 0;
  for (int i = 0; i < config.iterations; ++i) {
    const Eigen::Vector3d& a = sample[pick(rng)];
    const Eigen::Vector3d& b = sample[pick(rng)];
    const Eigen::Vector3d& c = sample[pick(rng)];
    Eigen::Vector3d normal = (b - a).cross(c - a);
    if (normal.norm() < 1e-6) continue;
    normal.normalize();
    if (normal.dot(up) < 0.0) normal = -normal;
    if (normal.dot(up) < min_cosine) continue;
    const double level = normal.dot(a);
    std::size_t count = 0;
    for (const Eigen::Vector3d& p : sample)
      count += std::abs(normal.dot(p) - level) < config.inlier_distance ? 1 : 0;
    // The lower of two planes as large: a floor under a table-sized patch of clutter.
    if (count > best_count || (count == best_count && level < best_level)) {
      best_count = count;
      best_normal = normal;
      best_level = level;
    }
  }
  if (best_count == 0) return std::nullopt;

  // Refit to every candidate near the winner, twice: the second fit's inliers come from the
  // first's plane, which no longer leans on three random points.
  FloorPlane plane;
  plane.up = best_normal;
  plane.level = best_level;
  for (int round = 0; round < 2; ++round) {
    std::vector<Eigen::Vector3d> inliers;
    for (const Eigen::Vector3d& p : candidates)
      if (std::abs(plane.heightOf(p)) < config.inlier_distance) inliers.push_back(p);
    if (inliers.size() < config.min_support) return std::nullopt;
    plane = fitPlane(inliers, up);
  }
  return plane;
}

}  // namespace rgbdmap
