#include "rgbdmap/slam/keyframe_floor.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

#include "rgbdmap/base/kinect_noise.hpp"
#include "rgbdmap/capture/lens_undistortion.hpp"

namespace rgbdmap {

KeyframeFloor::KeyframeFloor(const CameraIntrinsics& camera, double min_depth, double max_depth,
                             const Config& config)
    : config_(config),
      width_(camera.width),
      height_(camera.height),
      min_depth_(min_depth),
      max_depth_(max_depth) {
  config_.stride = std::max(1, config_.stride);
  config_.normal_step = std::max(1, config_.normal_step);
  const int step = config_.normal_step;
  std::vector<cv::Point2f> pixels;
  for (int v = config_.stride / 2; v + step < height_; v += config_.stride) {
    for (int u = config_.stride / 2; u + step < width_; u += config_.stride) {
      pixels.emplace_back(u, v);
      pixels.emplace_back(u + step, v);
      pixels.emplace_back(u, v + step);
    }
  }
  std::vector<cv::Point2f> undistorted;
  if (!pixels.empty()) LensUndistortion::rays(camera, pixels, undistorted);
  rays_.reserve(pixels.size() / 3);
  for (std::size_t i = 0; i + 2 < pixels.size(); i += 3) {
    rays_.push_back({static_cast<int>(pixels[i].x),
                     static_cast<int>(pixels[i].y),
                     {undistorted[i].x, undistorted[i].y},
                     {undistorted[i + 1].x, undistorted[i + 1].y},
                     {undistorted[i + 2].x, undistorted[i + 2].y}});
  }
}

const std::vector<KeyframeFloor::Sample>& KeyframeFloor::samples(const cv::Mat& depth) {
  std::vector<Sample>& out = samples_;
  out.clear();
  if (depth.type() != CV_32FC1 || depth.cols != width_ || depth.rows != height_) return out;
  out.reserve(rays_.size());
  const int step = config_.normal_step;
  auto usable = [this](double z) { return z >= min_depth_ && z <= max_depth_; };
  auto point = [](const Eigen::Vector2d& ray, double z) {
    return Eigen::Vector3d(ray.x() * z, ray.y() * z, z);
  };
  for (const Rays& r : rays_) {
    const double z = depth.at<float>(r.v, r.u);
    const double z_right = depth.at<float>(r.v, r.u + step);
    const double z_down = depth.at<float>(r.v + step, r.u);
    if (!usable(z) || !usable(z_right) || !usable(z_down)) continue;
    const Eigen::Vector3d p = point(r.at, z);
    const Eigen::Vector3d normal = (point(r.right, z_right) - p).cross(point(r.down, z_down) - p);
    if (normal.norm() <= 0.0) continue;
    out.push_back({p, normal.normalized(), kinectDepthSigma(static_cast<float>(z))});
  }
  return out;
}

bool KeyframeFloor::fits(const Sample& s, const CameraPlane& plane, double band) const {
  return std::abs(plane.normal.dot(s.point) - plane.distance) <=
             band + config_.band_sigmas * s.sigma &&
         std::abs(plane.normal.dot(s.normal)) >= std::cos(config_.max_normal_angle);
}

std::optional<CameraPlane> KeyframeFloor::refit(const std::vector<Sample>& samples,
                                                const CameraPlane& plane, double band) const {
  double weights = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::vector<const Sample*> inliers;
  for (const Sample& s : samples) {
    if (!fits(s, plane, band)) continue;
    const double w = 1.0 / (s.sigma * s.sigma);
    inliers.push_back(&s);
    weights += w;
    sum += w * s.point;
  }
  const double needed =
      std::max(static_cast<double>(config_.min_samples), config_.min_share * samples.size());
  if (static_cast<double>(inliers.size()) < needed) return std::nullopt;
  const Eigen::Vector3d centre = sum / weights;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();  // unweighted: how far the samples reach
  for (const Sample* s : inliers) {
    const Eigen::Vector3d d = s->point - centre;
    scatter += d * d.transpose() / (s->sigma * s->sigma);
    spread += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  CameraPlane out;
  out.normal = eig.eigenvectors().col(0);
  if (out.normal.dot(plane.normal) < 0.0) out.normal = -out.normal;
  out.distance = out.normal.dot(centre);
  out.inliers = inliers.size();
  const double n = static_cast<double>(inliers.size());
  const Eigen::Vector3d narrow = eig.eigenvectors().col(1);  // the larger eigenvalue is col(2)
  out.extent =
      std::sqrt(std::min(narrow.dot(spread * narrow),
                         eig.eigenvectors().col(2).dot(spread * eig.eigenvectors().col(2))) /
                n);
  if (out.extent < config_.min_extent) return std::nullopt;
  return out;
}

std::optional<CameraPlane> KeyframeFloor::settle(const std::vector<Sample>& samples,
                                                 CameraPlane plane) const {
  for (const double band : {config_.band, config_.middle_band, config_.final_band}) {
    const std::optional<CameraPlane> fit = refit(samples, plane, band);
    if (!fit) return std::nullopt;
    plane = *fit;
  }
  return plane;
}

std::optional<CameraPlane> KeyframeFloor::near(const cv::Mat& depth, const CameraPlane& guess) {
  const std::optional<CameraPlane> found = settle(samples(depth), guess);
  if (!found ||
      std::acos(std::clamp(found->normal.dot(guess.normal), -1.0, 1.0)) > config_.max_tilt)
    return std::nullopt;
  return found;
}

std::optional<CameraPlane> KeyframeFloor::discover(const cv::Mat& depth,
                                                   const Eigen::Vector3d& up) {
  const std::vector<Sample>& all = samples(depth);
  if (all.size() < 3) return std::nullopt;
  const Eigen::Vector3d u = up.normalized();
  const double min_cos = std::cos(config_.max_discovery_tilt);
  std::mt19937 random(config_.seed);
  std::uniform_int_distribution<std::size_t> pick(0, all.size() - 1);
  // Scored on a subsample: the best plane wins by thousands of samples, not by a few.
  const std::size_t step = std::max<std::size_t>(1, all.size() / 2000);
  std::optional<CameraPlane> best;
  std::size_t best_count = 0;
  for (int i = 0; i < config_.ransac_iterations; ++i) {
    const Eigen::Vector3d& a = all[pick(random)].point;
    const Eigen::Vector3d& b = all[pick(random)].point;
    const Eigen::Vector3d& c = all[pick(random)].point;
    Eigen::Vector3d normal = (b - a).cross(c - a);
    if (normal.norm() < 1e-9) continue;
    normal.normalize();
    if (normal.dot(u) < 0.0) normal = -normal;
    if (normal.dot(u) < min_cos) continue;
    const CameraPlane candidate{normal, normal.dot(a), 0};
    if (-candidate.distance < config_.min_height) continue;  // not far enough below the camera
    std::size_t count = 0;
    for (std::size_t k = 0; k < all.size(); k += step)
      if (fits(all[k], candidate, config_.middle_band)) ++count;
    if (count > best_count) {
      best_count = count;
      best = candidate;
    }
  }
  if (!best) return std::nullopt;
  const std::optional<CameraPlane> found = settle(all, *best);
  if (!found || found->normal.dot(u) < min_cos || -found->distance < config_.min_height)
    return std::nullopt;
  return found;
}

}  // namespace rgbdmap
