#include "rgbdmap/tracking/color_depth_calibrator.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <string>

#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/capture/lens_undistortion.hpp"
#include "rgbdmap/tracking/twist.hpp"

namespace rgbdmap {
namespace {

// The unknowns: the extrinsic's left increment (translation, rotation) and the focal length's
// log (one for both axes: their ratio stays the declared one, which cameras keep to well within
// the 0.5% the calibration aims at, and a free ratio wanders along the outlines' few directions).
using Vector7 = Eigen::Matrix<double, 7, 1>;
using Matrix7 = Eigen::Matrix<double, 7, 7>;

// A point of an object's outline in the depth camera: where depth jumps from it to something
// farther, half a pixel out, and the point one pixel farther out at its depth (which way the
// outline's normal points once both are in the colour image).
struct Outline {
  Eigen::Vector3f point;
  Eigen::Vector3f beyond;
};

constexpr int kMaxSamples = 129;  // of one search: +-32 px every half pixel

// A colour image's intensity gradient.
struct ColorGradient {
  cv::Mat gx, gy;  // CV_32FC1
};

// What one frame's outlines contribute to the normal equations.
struct FrameSystem {
  Matrix7 H = Matrix7::Zero();
  Vector7 b = Vector7::Zero();
  double squares = 0.0;  // of the gaps, pixels
  std::size_t count = 0;
  std::size_t close = 0;  // gaps under a pixel
};

bool bilinear(const ColorGradient& image, float u, float v, float& gx, float& gy) {
  if (!(u >= 0.0f && v >= 0.0f && u < image.gx.cols - 1.0f && v < image.gx.rows - 1.0f))
    return false;
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  const float a = u - x, c = v - y;
  auto at = [&](const cv::Mat& m) {
    const float* r0 = m.ptr<float>(y) + x;
    const float* r1 = m.ptr<float>(y + 1) + x;
    return (1 - c) * ((1 - a) * r0[0] + a * r0[1]) + c * ((1 - a) * r1[0] + a * r1[1]);
  };
  gx = at(image.gx);
  gy = at(image.gy);
  return true;
}

std::vector<Outline> outlines(const cv::Mat& depth, const CameraIntrinsics& camera,
                              const ColorDepthCalibrator::Config& config) {
  std::vector<Outline> out;
  // Through the depth camera's lens: a registered camera's depth shares the colour lens.
  std::vector<cv::Point2f> pixel(1), normalised(1);
  auto ray = [&](float u, float v, float z) {
    if (!camera.hasDistortion())
      return Eigen::Vector3f(static_cast<float>((u - camera.cx) / camera.fx) * z,
                             static_cast<float>((v - camera.cy) / camera.fy) * z, z);
    pixel[0] = {u, v};
    LensUndistortion::rays(camera, pixel, normalised);
    return Eigen::Vector3f(normalised[0].x * z, normalised[0].y * z, z);
  };
  const int steps[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (int v = 1; v + 1 < depth.rows; ++v) {
    for (int u = 1; u + 1 < depth.cols; ++u) {
      const float z = depth.at<float>(v, u);
      if (!(z >= config.min_depth && z <= config.max_depth)) continue;
      for (const auto& s : steps) {
        const float beside = depth.at<float>(v + s[1], u + s[0]);
        // A missing neighbour says nothing: it may be a shadow of this surface as well as a jump.
        if (!(beside > z * 1.05f + static_cast<float>(config.min_jump))) continue;
        out.push_back(
            {ray(u + 0.5f * s[0], v + 0.5f * s[1], z), ray(u + 1.5f * s[0], v + 1.5f * s[1], z)});
      }
    }
  }
  const std::size_t limit = static_cast<std::size_t>(std::max(1, config.max_edges_per_frame));
  if (out.size() > limit) {
    // Evenly thinned: every k-th along the rows keeps every outline represented.
    const double stride = static_cast<double>(out.size()) / static_cast<double>(limit);
    std::vector<Outline> thinned;
    for (std::size_t i = 0; i < limit; ++i)
      thinned.push_back(out[static_cast<std::size_t>(static_cast<double>(i) * stride)]);
    out.swap(thinned);
  }
  return out;
}

}  // namespace

ColorDepthCalibrator::ColorDepthCalibrator(const Config& config, const CameraIntrinsics& color,
                                           const CameraIntrinsics& depth)
    : config_(config), color_(color), depth_(depth) {
  if (!(config.search_px >= 2.0 && 2 * config.search_px / 0.5 + 1 <= kMaxSamples))
    throw std::invalid_argument("ColorDepthCalibrator: search_px must be within 2-32 px");
}

CalibrationReport ColorDepthCalibrator::estimate(const std::vector<CalibrationFrame>& frames,
                                                 const ColorDepthCalibration& guess,
                                                 WorkerPool& pool) const {
  std::vector<std::vector<Outline>> edges(frames.size());
  std::vector<ColorGradient> gradients(frames.size());
  auto prepare = [&](std::size_t f) {
    edges[f] = outlines(frames[f].depth, depth_, config_);
    cv::Sobel(frames[f].gray, gradients[f].gx, CV_32F, 1, 0, 1, 0.5);
    cv::Sobel(frames[f].gray, gradients[f].gy, CV_32F, 0, 1, 1, 0.5);
  };
  pool.run(frames.size(), prepare);

  const bool depth_focal = config_.estimate_depth_focal;
  std::vector<FrameSystem> systems(frames.size());
  // Matches every outline against the colour edges of its frame within `search_px`.
  auto match = [&](const ColorDepthCalibration& x, double search_px) {
    const double fx = x.fx, fy = x.fy, cx = color_.cx, cy = color_.cy;
    const Eigen::Matrix3f R = x.color_from_depth.linear().cast<float>();
    const Eigen::Vector3f t = x.color_from_depth.translation().cast<float>();
    // A longer depth focal length puts the outlines nearer the view's centre.
    const float lateral = static_cast<float>(1.0 / x.depth_focal_scale);
    const Eigen::Vector3f scale(lateral, lateral, 1.0f);
    const float search = static_cast<float>(search_px);
    const float min_gradient = static_cast<float>(config_.min_gradient);
    const float unique = static_cast<float>(config_.unique);
    auto body = [&](std::size_t f) {
      FrameSystem system;
      const ColorGradient& image = gradients[f];
      for (const Outline& outline : edges[f]) {
        const Eigen::Vector3f in_depth = outline.point.cwiseProduct(scale);
        const Eigen::Vector3f p = R * in_depth + t;
        const Eigen::Vector3f q = R * outline.beyond.cwiseProduct(scale) + t;
        if (p.z() < 0.1f || q.z() < 0.1f) continue;
        const Eigen::Vector2f u(static_cast<float>(fx * p.x() / p.z() + cx),
                                static_cast<float>(fy * p.y() / p.z() + cy));
        const Eigen::Vector2f beyond(static_cast<float>(fx * q.x() / q.z() + cx),
                                     static_cast<float>(fy * q.y() / q.z() + cy));
        if ((beyond - u).norm() < 1e-3f) continue;
        const Eigen::Vector2f n = (beyond - u).normalized();
        // The intensity change across the outline at each half pixel of the search range.
        const float step = 0.5f;
        const int samples = 2 * static_cast<int>(search / step) + 1;
        float change[kMaxSamples];
        bool inside = true;
        int best = 0;
        for (int i = 0; i < samples && inside; ++i) {
          float gx = 0.0f, gy = 0.0f;
          const Eigen::Vector2f at = u + (i * step - search) * n;
          inside = bilinear(image, at.x(), at.y(), gx, gy);
          change[i] = std::abs(gx * n.x() + gy * n.y());
          if (change[i] > change[best]) best = i;
        }
        // No edge, the strongest at the end of the range (the edge may lie beyond it), or
        // another as strong nearby (texture: which one is the outline's cannot be told).
        if (!inside || change[best] < min_gradient || best == 0 || best == samples - 1) continue;
        float rival = 0.0f;
        for (int i = 0; i < samples; ++i)
          if (std::abs(i - best) * step > 1.5f) rival = std::max(rival, change[i]);
        if (rival > unique * change[best]) continue;
        // Sub-sample: the vertex of the parabola through the peak and its neighbours.
        const float before = change[best - 1], peak = change[best], after = change[best + 1];
        const float curvature = before - 2.0f * peak + after;
        const float offset =
            curvature < 0.0f ? std::clamp(0.5f * (before - after) / curvature, -0.5f, 0.5f) : 0.f;
        const float best_t = best * step - search;
        const double gap = -(best_t + offset * step);  // projection minus colour edge, along n

        // Jacobian of (projection . n): extrinsic (left increment), log focal length.
        const double z = p.z();
        const Eigen::Vector3d dp(n.x() * fx / z, n.y() * fy / z,
                                 -(n.x() * fx * p.x() + n.y() * fy * p.y()) / (z * z));
        const Eigen::Vector3d pd = p.cast<double>();
        Vector7 J;
        J.head<3>() = dp;
        J.segment<3>(3) = pd.cross(dp);
        if (depth_focal)  // the depth camera's point moves in by the log focal length's step
          J(6) = dp.dot(R.cast<double>() * Eigen::Vector3d(-in_depth.x(), -in_depth.y(), 0.0));
        else
          J(6) = (n.x() * fx * p.x() + n.y() * fy * p.y()) / z;
        const double w = std::abs(gap) <= 1.0 ? 1.0 : 1.0 / std::abs(gap);  // Huber, 1 px
        system.H.noalias() += w * J * J.transpose();
        system.b += w * gap * J;
        system.squares += gap * gap;
        ++system.count;
        if (std::abs(gap) < 1.0) ++system.close;
      }
      systems[f] = system;
    };
    pool.run(frames.size(), body);
    FrameSystem total;
    for (const FrameSystem& s : systems) {
      total.H += s.H;
      total.b += s.b;
      total.squares += s.squares;
      total.count += s.count;
      total.close += s.close;
    }
    return total;
  };

  // Gauss-Newton from `start`, at full resolution only (halved images put the outlines off
  // their edges: the blur mixes an object with what lies behind it), the search narrowed instead
  // as the estimate closes in.
  auto refine = [&](ColorDepthCalibration current) {
    for (double search = config_.search_px; search >= 1.99; search /= 2) {
      for (int iteration = 0; iteration < config_.iterations; ++iteration) {
        FrameSystem system = match(current, search);
        if (system.count < 100)
          throw std::runtime_error("too few outlines of objects against their background (" +
                                   std::to_string(system.count) +
                                   " found): film objects in front of others, within " +
                                   std::to_string(config_.max_depth) + " m");
        system.H.diagonal() *= 1.0 + 1e-6;
        if (!config_.estimate_depth_z) {
          // No move of the depth camera along the colour camera's view (what a turn adds to it
          // through the left increment is taken back after the step).
          system.H.row(2).setZero();
          system.H.col(2).setZero();
          system.H(2, 2) = 1.0;
          system.b(2) = 0.0;
        }
        const Vector7 step = -system.H.ldlt().solve(system.b);
        if (!step.allFinite()) throw std::runtime_error("the estimate diverged");
        current.color_from_depth = expSE3(step.head<6>()) * current.color_from_depth;
        if (depth_focal) {
          current.depth_focal_scale *= std::exp(step(6));
        } else {
          current.fx *= std::exp(step(6));
          current.fy *= std::exp(step(6));
        }
        if (!config_.estimate_depth_z)
          current.color_from_depth.translation().z() = guess.color_from_depth.translation().z();
        // Far from any camera's: matched to texture rather than outlines, not a calibration.
        const Eigen::Isometry3d moved = guess.color_from_depth.inverse() * current.color_from_depth;
        const double focal = depth_focal ? current.depth_focal_scale / guess.depth_focal_scale
                                         : current.fx / guess.fx;
        if (std::abs(std::log(focal)) > 0.2 || moved.translation().norm() > 0.1 ||
            Eigen::AngleAxisd(moved.linear()).angle() > 10.0 * M_PI / 180.0)
          throw std::runtime_error(
              "the estimate ran off (focal length " + std::to_string(focal) +
              " times the guess, depth camera " +
              std::to_string(moved.translation().norm() * 1000.0) + " mm from the guess) on " +
              std::to_string(system.count) +
              " outline points: film objects standing before others from nearer and from more "
              "sides, or give a guess nearer the truth (camera.depth_* keys)");
        if (step.head<3>().norm() < 1e-5 && step.segment<3>(3).norm() < 1e-5 &&
            std::abs(step(6)) < 1e-5)
          break;
      }
    }
    return current;
  };

  // From the guess, and from the depth camera moved across the view by up to the baseline's own
  // size (a guess of "registered" for lenses 2.5 cm apart puts outlines 10 px and more off their
  // edges, out of the search's reach: on a rendered floor it converged elsewhere), the start that
  // brings most outlines within a pixel of an edge. Of the ends, the one that does.
  // With the depth camera's focal length unknown, its guess may be 10% off as well (outlines
  // 30 px off their edges at the image's sides, where the nearest edge is often the wrong one):
  // then each focal length across that range is a start too, with its best offset, and each is
  // refined (which start brings most outlines within a pixel tells little that far off).
  std::vector<ColorDepthCalibration> starts = {guess};
  const double focal_step = std::max(config_.start_focal_step, 1e-3);
  // Counted in whole steps, so that the middle one is the guess's focal length exactly.
  const int focal_steps =
      depth_focal ? static_cast<int>(std::floor(config_.start_focal_range / focal_step + 1e-9)) : 0;
  for (int i = -focal_steps; i <= focal_steps; ++i) {
    ColorDepthCalibration focal_start = guess;
    focal_start.depth_focal_scale *= 1.0 + i * focal_step;
    ColorDepthCalibration beside = focal_start;
    std::size_t most_close = match(focal_start, config_.search_px / 2).close;
    for (double dx = -config_.start_offset_m; dx <= config_.start_offset_m + 1e-9;
         dx += config_.start_step_m) {
      ColorDepthCalibration start = focal_start;
      start.color_from_depth.translation() += Eigen::Vector3d(dx, 0.0, 0.0);
      const std::size_t close = match(start, config_.search_px / 2).close;
      if (close > most_close) {
        most_close = close;
        beside = start;
      }
    }
    const bool at_guess = beside.depth_focal_scale == guess.depth_focal_scale &&
                          beside.color_from_depth.isApprox(guess.color_from_depth);
    if (!at_guess) starts.push_back(beside);
  }
  // Each end judged, and reported, by its matches within the last search range.
  const double final_search = 2.0;
  std::optional<ColorDepthCalibration> current;
  FrameSystem at_estimate;
  std::string failure;
  for (const ColorDepthCalibration& start : starts) {
    try {
      const ColorDepthCalibration end = refine(start);
      const FrameSystem matched = match(end, final_search);
      if (!current || matched.close > at_estimate.close) {
        current = end;
        at_estimate = matched;
      }
    } catch (const std::runtime_error& e) {
      if (failure.empty()) failure = e.what();
    }
  }
  if (!current) throw std::runtime_error(failure);

  CalibrationReport report;
  report.calibration = *current;
  const FrameSystem at_guess = match(guess, final_search);
  report.edges_before = at_guess.count;
  report.rms_before = std::sqrt(at_guess.squares / std::max<std::size_t>(1, at_guess.count));
  report.edges_after = at_estimate.count;
  report.rms_after = std::sqrt(at_estimate.squares / std::max<std::size_t>(1, at_estimate.count));
  // Standard deviations as if the gaps were independent (neighbouring outline points are not,
  // so the truth spreads wider): what tells a well-posed recording from a poor one.
  const Matrix7 covariance = at_estimate.H.inverse() * report.rms_after * report.rms_after;
  report.translation_sd = std::sqrt(covariance.block<3, 3>(0, 0).trace());
  report.rotation_sd = std::sqrt(covariance.block<3, 3>(3, 3).trace());
  report.focal_sd = std::sqrt(covariance(6, 6));
  return report;
}

}  // namespace rgbdmap
