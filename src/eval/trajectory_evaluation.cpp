#include "rgbdmap/eval/trajectory_evaluation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/association.hpp"

namespace rgbdmap {
namespace {

// Index of the stamp closest to t in a sorted list (evaluate_rpe.py's find_closest_index).
std::size_t closestIndex(const std::vector<double>& stamps, double t) {
  const auto after = std::lower_bound(stamps.begin(), stamps.end(), t);
  if (after == stamps.begin()) return 0;
  if (after == stamps.end()) return stamps.size() - 1;
  const std::size_t j = static_cast<std::size_t>(after - stamps.begin());
  return (t - stamps[j - 1] <= stamps[j] - t) ? j - 1 : j;
}

// (groundtruth, estimate) index pairs by TUM's rule; at least 3, else InputError naming `what`.
std::vector<std::pair<std::size_t, std::size_t>> associatedPoses(const Trajectory& estimate,
                                                                 const Trajectory& groundtruth,
                                                                 double max_difference,
                                                                 const std::string& what) {
  auto pairs = associate(groundtruth.timestamps(), estimate.timestamps(), max_difference);
  if (pairs.size() < 3)
    throw InputError(what + ": only " + std::to_string(pairs.size()) +
                     " estimated poses have a groundtruth stamp within " +
                     std::to_string(max_difference) + " s; need at least 3");
  return pairs;
}

}  // namespace

Eigen::Isometry3d alignRigid(const std::vector<Eigen::Vector3d>& from,
                             const std::vector<Eigen::Vector3d>& to) {
  if (from.size() != to.size() || from.size() < 3)
    throw std::invalid_argument("alignRigid: needs at least 3 point pairs");
  Eigen::Matrix3Xd source(3, from.size()), target(3, to.size());
  for (std::size_t i = 0; i < from.size(); ++i) {
    source.col(static_cast<Eigen::Index>(i)) = from[i];
    target.col(static_cast<Eigen::Index>(i)) = to[i];
  }
  // Eigen's Umeyama without scale is Horn's closed form via the SVD of the cross-covariance,
  // with the same reflection guard as evaluate_ate.py.
  Eigen::Isometry3d transform;
  transform.matrix() = Eigen::umeyama(source, target, false);
  return transform;
}

ErrorStatistics errorStatistics(std::vector<double> errors) {
  ErrorStatistics s;
  s.count = errors.size();
  if (errors.empty()) return s;
  double sum = 0.0, squares = 0.0;
  for (const double e : errors) {
    sum += e;
    squares += e * e;
    s.max = std::max(s.max, e);
  }
  const double n = static_cast<double>(errors.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(squares / n);
  // numpy.median: the mean of the two middle values for an even count.
  const std::size_t mid = errors.size() / 2;
  std::nth_element(errors.begin(), errors.begin() + static_cast<long>(mid), errors.end());
  s.median = errors[mid];
  if (errors.size() % 2 == 0)
    s.median = 0.5 * (s.median +
                      *std::max_element(errors.begin(), errors.begin() + static_cast<long>(mid)));
  return s;
}

AbsoluteTrajectoryError absoluteTrajectoryError(const Trajectory& estimate,
                                                const Trajectory& groundtruth,
                                                double max_difference) {
  const auto pairs = associatedPoses(estimate, groundtruth, max_difference, "ATE");
  std::vector<Eigen::Vector3d> truth, estimated;
  for (const auto& [g, e] : pairs) {
    truth.push_back(groundtruth[g].pose.translation());
    estimated.push_back(estimate[e].pose.translation());
  }
  AbsoluteTrajectoryError ate;
  ate.alignment = alignRigid(estimated, truth);
  std::vector<double> residuals;
  residuals.reserve(truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i)
    residuals.push_back((ate.alignment * estimated[i] - truth[i]).norm());
  ate.translation = errorStatistics(std::move(residuals));
  return ate;
}

Eigen::Isometry3d alignViews(const Trajectory& estimate, const Trajectory& groundtruth,
                             double max_difference) {
  const auto pairs = associatedPoses(estimate, groundtruth, max_difference, "alignment");
  // Camera frame: x right, y down, z along the optical axis; tan(30 deg) = 0.577 at 2 m is
  // 1.15 m, tan(22.5 deg) 0.83 m.
  const Eigen::Vector3d view[] = {
      {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}, {0.0, 0.0, 3.0}, {-1.15, 0.0, 2.0}, {0.0, -0.83, 2.0}};
  std::vector<Eigen::Vector3d> truth, estimated;
  truth.reserve(pairs.size() * std::size(view));
  estimated.reserve(pairs.size() * std::size(view));
  for (const auto& [g, e] : pairs) {
    for (const Eigen::Vector3d& v : view) {
      truth.push_back(groundtruth[g].pose * v);
      estimated.push_back(estimate[e].pose * v);
    }
  }
  return alignRigid(estimated, truth);
}

RelativePoseError relativePoseError(const Trajectory& estimate, const Trajectory& groundtruth,
                                    double interval) {
  if (estimate.size() < 2 || groundtruth.size() < 2)
    throw InputError("RPE: needs at least 2 estimated and 2 groundtruth poses");
  const std::vector<double> est_stamps = estimate.timestamps();
  const std::vector<double> gt_stamps = groundtruth.timestamps();
  std::vector<double> spacing;
  for (std::size_t i = 1; i < gt_stamps.size(); ++i)
    spacing.push_back(gt_stamps[i] - gt_stamps[i - 1]);
  const double max_gt_difference = 2.0 * errorStatistics(spacing).median;

  std::vector<double> translation, rotation;
  for (std::size_t i = 0; i < est_stamps.size(); ++i) {
    const std::size_t j = closestIndex(est_stamps, est_stamps[i] + interval);
    if (j == est_stamps.size() - 1) continue;  // as evaluate_rpe.py: the end is not a partner
    const std::size_t gi = closestIndex(gt_stamps, est_stamps[i]);
    const std::size_t gj = closestIndex(gt_stamps, est_stamps[j]);
    if (std::abs(gt_stamps[gi] - est_stamps[i]) > max_gt_difference ||
        std::abs(gt_stamps[gj] - est_stamps[j]) > max_gt_difference)
      continue;
    const Eigen::Isometry3d truth_motion = groundtruth[gi].pose.inverse() * groundtruth[gj].pose;
    const Eigen::Isometry3d estimated_motion = estimate[i].pose.inverse() * estimate[j].pose;
    const Eigen::Isometry3d error = truth_motion.inverse() * estimated_motion;
    translation.push_back(error.translation().norm());
    rotation.push_back(Eigen::AngleAxisd(error.linear()).angle() * 180.0 / M_PI);
  }
  if (translation.empty())
    throw InputError("RPE: no pose pair " + std::to_string(interval) +
                     " s apart with groundtruth at both ends (is the estimate shorter than the "
                     "interval, or far from the groundtruth's stamps?)");
  RelativePoseError rpe;
  rpe.translation = errorStatistics(std::move(translation));
  rpe.rotation = errorStatistics(std::move(rotation));
  return rpe;
}

}  // namespace rgbdmap
