#include "rgbdmap/slam/place_matcher.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/features2d.hpp>
#include <unordered_map>

#include "rgbdmap/slam/motion.hpp"
#include "rgbdmap/tracking/relocaliser.hpp"

namespace rgbdmap {
namespace {

using Points = std::vector<Eigen::Vector3d>;

void ratioMatches(const cv::Mat& a, const cv::Mat& b, std::vector<cv::DMatch>& matches) {
  matches.clear();
  if (a.rows < 2 || b.rows < 2) return;
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(a, b, knn, 2);
  // Lowe's ratio test, as loop closure's: distinctive matches only.
  for (const auto& m : knn)
    if (m.size() == 2 && m[0].distance <= 0.8f * m[1].distance) matches.push_back(m[0]);
}

// The reference's densest level as points (x y z), at most `max_points`, evenly spread.
Points surfaceOf(const PackedReference& packed, std::size_t max_points) {
  AlignmentReference reference;
  packed.expand(reference);
  const AlignmentReference::Level* densest = nullptr;
  for (const auto& level : reference.levels)
    if (!densest || level.points.size() > densest->points.size()) densest = &level;
  Points points;
  if (!densest || densest->points.empty()) return points;
  const std::size_t stride = std::max<std::size_t>(1, densest->points.size() / max_points);
  for (std::size_t i = 0; i < densest->points.size(); i += stride)
    points.push_back(densest->points[i].head<3>().cast<double>());
  return points;
}

// Nearest-point lookup in a grid of `cell`-sized cubes (the search looks one cell around).
class PointGrid {
 public:
  PointGrid(const Points& points, double cell) : points_(points), cell_(cell) {
    for (std::size_t i = 0; i < points.size(); ++i) cells_[key(cellOf(points[i]))].push_back(i);
  }
  // The points within `radius` (<= cell) of `p`.
  void within(const Eigen::Vector3d& p, double radius, std::vector<std::size_t>& out) const {
    out.clear();
    const Eigen::Vector3i c = cellOf(p);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (const std::size_t i : it->second)
            if ((points_[i] - p).squaredNorm() <= radius * radius) out.push_back(i);
        }
  }
  // The nearest point within `radius` (<= cell), or -1.
  long nearest(const Eigen::Vector3d& p, double radius) const {
    const Eigen::Vector3i c = cellOf(p);
    long best = -1;
    double best_d2 = radius * radius;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (const std::size_t i : it->second) {
            const double d2 = (points_[i] - p).squaredNorm();
            if (d2 < best_d2) {
              best_d2 = d2;
              best = static_cast<long>(i);
            }
          }
        }
    return best;
  }

 private:
  Eigen::Vector3i cellOf(const Eigen::Vector3d& p) const {
    return (p / cell_).array().floor().cast<int>();
  }
  static std::int64_t key(const Eigen::Vector3i& c) {
    return (static_cast<std::int64_t>(c.x() & 0x1fffff) << 42) |
           (static_cast<std::int64_t>(c.y() & 0x1fffff) << 21) | (c.z() & 0x1fffff);
  }
  const Points& points_;
  double cell_;
  std::unordered_map<std::int64_t, std::vector<std::size_t>> cells_;
};

struct IcpResult {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  std::size_t inliers = 0;
  double rms = 0.0;
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();  // per point
};

// Each point's surface normal from its neighbours within `radius` (zero where too few).
Points normalsOf(const Points& points, const PointGrid& grid, double radius) {
  Points normals(points.size(), Eigen::Vector3d::Zero());
  std::vector<std::size_t> near;
  for (std::size_t i = 0; i < points.size(); ++i) {
    grid.within(points[i], radius, near);
    if (near.size() < 6) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const std::size_t j : near) mean += points[j];
    mean /= static_cast<double>(near.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const std::size_t j : near) {
      const Eigen::Vector3d d = points[j] - mean;
      covariance += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
    // Planar enough: the smallest spread well under the middle one.
    if (eigen.eigenvalues()(0) > 0.1 * eigen.eigenvalues()(1)) continue;
    normals[i] = eigen.eigenvectors().col(0);
  }
  return normals;
}

// Point-to-plane ICP of `query` (its camera) onto `target` (the candidate's), from `start`:
// Gauss-Newton on the distances to the target's local planes, pairs within a radius shrinking
// from max_pair to inlier.
IcpResult icp(const Points& query, const Points& target, const Eigen::Isometry3d& start,
              const PlaceMatcher::Options& o) {
  const PointGrid grid(target, o.max_pair);
  const Points normals = normalsOf(target, grid, 0.02);
  IcpResult r;
  r.pose = start;
  double radius = o.max_pair;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  // Adds a pair's row to the normal equations; returns its squared distance.
  const auto accumulate = [&](const Eigen::Vector3d& p, std::size_t j, Matrix6d& h, Vector6d& g) {
    const Eigen::Vector3d& n = normals[j];
    const double e = n.dot(p - target[j]);
    Vector6d jacobian;
    jacobian.head<3>() = n;
    jacobian.tail<3>() = p.cross(n);
    h += jacobian * jacobian.transpose();
    g += jacobian * e;
    return e * e;
  };
  for (int iteration = 0; iteration < 30; ++iteration) {
    Matrix6d h = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    std::size_t pairs = 0;
    for (const Eigen::Vector3d& q : query) {
      const Eigen::Vector3d p = r.pose * q;
      const long j = grid.nearest(p, radius);
      if (j < 0 || normals[static_cast<std::size_t>(j)].isZero()) continue;
      accumulate(p, static_cast<std::size_t>(j), h, g);
      ++pairs;
    }
    if (pairs < 12) return r;
    const Vector6d step = h.ldlt().solve(-g);
    if (!step.allFinite()) return r;
    Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
    const double angle = step.tail<3>().norm();
    if (angle > 0)
      delta.linear() = Eigen::AngleAxisd(angle, step.tail<3>() / angle).toRotationMatrix();
    delta.translation() = step.head<3>();
    r.pose = delta * r.pose;
    radius = std::max(o.inlier, radius * 0.7);
    if (radius <= o.inlier && step.norm() < 1e-6) break;
  }
  // The inliers at the final pose: their count, spread and how well they pin the pose down.
  Matrix6d h = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  double sum = 0.0;
  for (const Eigen::Vector3d& q : query) {
    const Eigen::Vector3d p = r.pose * q;
    const long j = grid.nearest(p, o.inlier);
    if (j < 0) continue;
    ++r.inliers;
    if (normals[static_cast<std::size_t>(j)].isZero()) continue;
    sum += accumulate(p, static_cast<std::size_t>(j), h, g);
  }
  if (r.inliers == 0) return r;
  r.rms = std::sqrt(sum / static_cast<double>(r.inliers));
  const double sigma = std::max(r.rms, 0.002);
  r.information = h / static_cast<double>(r.inliers) / (sigma * sigma);
  return r;
}

}  // namespace

PlaceMatcher::PlaceMatcher(const CameraIntrinsics& camera, const LoopOptions& loop, Options options)
    : camera_(camera), loop_(loop), options_(options) {}

int PlaceMatcher::similarity(const PlaceRecognition::Place& a,
                             const PlaceRecognition::Place& b) const {
  std::vector<cv::DMatch> matches;
  ratioMatches(a.view.descriptors, b.view.descriptors, matches);
  return static_cast<int>(matches.size());
}

std::optional<LoopMeasurement> PlaceMatcher::match(const PlaceRecognition::Place& candidate,
                                                   const PlaceRecognition::Place& query) const {
  std::vector<cv::DMatch> matches;
  ratioMatches(candidate.view.descriptors, query.view.descriptors, matches);
  if (static_cast<int>(matches.size()) < loop_.min_matches) return std::nullopt;
  // PnP: the candidate's 3-D points against where the query saw its own (projected).
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (const cv::DMatch& m : matches) {
    const cv::Point3f& q = query.view.points[static_cast<std::size_t>(m.trainIdx)];
    if (!(q.z > 0.0f)) continue;
    object.push_back(candidate.view.points[static_cast<std::size_t>(m.queryIdx)]);
    image.emplace_back(static_cast<float>(camera_.fx * q.x / q.z + camera_.cx),
                       static_cast<float>(camera_.fy * q.y / q.z + camera_.cy));
  }
  int inliers = 0;
  const std::optional<Eigen::Isometry3d> candidate_in_query =
      solvePnp(object, image, camera_, false, loop_.min_inliers, &inliers);
  if (!candidate_in_query) return std::nullopt;
  const Eigen::Isometry3d by_features = candidate_in_query->inverse();  // X_cand^-1 X_query
  if (by_features.translation().norm() > loop_.max_distance) return std::nullopt;

  const Points query_points = surfaceOf(query.reference, options_.max_points);
  const Points target = surfaceOf(candidate.reference, std::numeric_limits<std::size_t>::max());
  if (query_points.empty() || target.empty()) return std::nullopt;
  IcpResult aligned = icp(query_points, target, by_features, options_);
  const double overlap =
      static_cast<double>(aligned.inliers) / static_cast<double>(query_points.size());
  if (overlap < options_.min_overlap || aligned.rms > options_.max_rms) return std::nullopt;
  const Eigen::Isometry3d change = by_features.inverse() * aligned.pose;
  if (change.translation().norm() > loop_.max_disagreement_translation ||
      rotationAngle(change) > loop_.max_disagreement_rotation ||
      aligned.pose.translation().norm() > loop_.max_distance)
    return std::nullopt;
  LoopMeasurement loop;
  aligned.pose.linear() = Eigen::Quaterniond(aligned.pose.linear()).normalized().toRotationMatrix();
  loop.later_in_earlier = aligned.pose;
  loop.information = aligned.information;
  loop.matches = static_cast<int>(matches.size());
  loop.inliers = inliers;
  loop.overlap = overlap;
  return loop;
}

}  // namespace rgbdmap
