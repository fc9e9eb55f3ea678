#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap {

// A plane in a camera's frame: the points x with normal . x == distance (normal unit). The floor
// below a camera has its normal pointing up and a negative distance (minus the camera's height).
struct CameraPlane {
  Eigen::Vector3d normal = -Eigen::Vector3d::UnitY();
  double distance = 0.0;
  std::size_t inliers = 0;  // depth samples within the band of the fitted plane
  double extent = 0.0;      // m: standard deviation of the inliers along the narrower axis
};

// The floor in one keyframe's depth image. With a guess (the floor where the graph puts the
// camera), the plane of the samples within `band` of it, refitted as the band narrows; without
// one, first the plane RANSAC finds with the most samples, facing within `max_discovery_tilt` of
// `up` and at least `min_height` below the camera (a table top under a camera held at standing
// height is smaller than the floor, and nearer). Either way the plane must hold `min_share` of
// the samples and spread over `min_extent` both ways: a strip says little about its tilt across
// itself (CameraPlane::extent says how much). Samples are every `stride`-th pixel of every
// `stride`-th row, undistorted. On rendered floors a fit is within 0.09 deg and 2 mm of the true
// floor (one standard deviation).
class KeyframeFloor {
 public:
  struct Config {
    int stride = 4;
    // Bands around the plane as it is refitted: m, plus band_sigmas sigma(z). Wall bases and
    // low furniture within a band tilt a fit; samples must also face the plane's way, within
    // max_normal_angle (a sample's normal is from its neighbours normal_step pixels on).
    double band = 0.05;
    double middle_band = 0.02;
    double final_band = 0.0;
    double band_sigmas = 2.5;
    double max_normal_angle = 0.35;  // rad (20 deg)
    int normal_step = 8;
    double max_tilt = 0.05;           // rad between a guess and the plane found near it
    double max_discovery_tilt = 0.6;  // rad between up and a discovered plane
    double min_height = 0.5;          // m below the camera, for a discovered plane
    double min_share = 0.03;          // of the valid samples
    std::size_t min_samples = 300;
    double min_extent = 0.12;  // m: standard deviation of the inliers along both in-plane axes
    int ransac_iterations = 200;
    std::uint32_t seed = 1;
  };

  KeyframeFloor(const CameraIntrinsics& camera, double min_depth, double max_depth,
                const Config& config);

  // Not const: both reuse one buffer of samples (megabytes a keyframe, zeroed by the kernel
  // when allocated afresh).
  std::optional<CameraPlane> near(const cv::Mat& depth, const CameraPlane& guess);
  std::optional<CameraPlane> discover(const cv::Mat& depth, const Eigen::Vector3d& up);

 private:
  struct Sample {
    Eigen::Vector3d point;
    Eigen::Vector3d normal;  // unit; its sign is arbitrary
    double sigma;            // of its depth
  };
  // The samples of `depth` into samples_.
  const std::vector<Sample>& samples(const cv::Mat& depth);
  bool fits(const Sample& s, const CameraPlane& plane, double band) const;
  // Least squares (weights 1 / sigma(z)^2) through the samples that fit `plane` within band,
  // normal on plane's side; none when too few samples or too narrow a spread.
  std::optional<CameraPlane> refit(const std::vector<Sample>& samples, const CameraPlane& plane,
                                   double band) const;
  std::optional<CameraPlane> settle(const std::vector<Sample>& samples, CameraPlane plane) const;

  Config config_;
  int width_ = 0, height_ = 0;
  double min_depth_, max_depth_;
  // x/z, y/z of each sampled pixel and its neighbours normal_step on in its row and column.
  struct Rays {
    int u, v;
    Eigen::Vector2d at, right, down;
  };
  std::vector<Rays> rays_;
  std::vector<Sample> samples_;
};

}  // namespace rgbdmap
