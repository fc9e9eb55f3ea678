#include "rgbdmap/tracking/dense_aligner.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "rgbdmap/tracking/twist.hpp"

namespace rgbdmap {
namespace {

using Vector6f = Eigen::Matrix<float, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

using Residual = DenseAligner::Residual;

// Jacobian row of a residual whose gradient with respect to the warped point p is g:
// (g, p x g) for a left increment (translation, rotation). Scalar code: gcc's array-bounds
// analysis misreads Eigen's vectorised 3-vector cross product.
Vector6f jacobianRow(const Eigen::Vector3f& p, float gx, float gy, float gz) {
  Vector6f j;
  j << gx, gy, gz, p.y() * gz - p.z() * gy, p.z() * gx - p.x() * gz, p.x() * gy - p.y() * gx;
  return j;
}

// Robust spread (1.4826 * median absolute value) of every 4th value, which is plenty.
float robustSigma(std::vector<float>& values, float fallback) {
  if (values.size() < 16) return fallback;
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return std::max(1.4826f * *mid, 1e-6f);
}

float huberWeight(float r_over_sigma, float k) {
  const float a = std::abs(r_over_sigma);
  return a <= k ? 1.0f : k / a;
}

// Bilinear lookup of all sampled quantities at (u, v); false when a depth corner is missing
// (then only the intensity part, which is never missing, is valid: depth fields are zeroed).
PixelSample bilinear(const PyramidLevel& level, float u, float v, bool& depth_ok) {
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  const float ax = u - static_cast<float>(x), ay = v - static_cast<float>(y);
  const std::size_t w = static_cast<std::size_t>(level.camera.width);
  const PixelSample* p =
      &level.samples[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x)];
  const PixelSample& s00 = p[0];
  const PixelSample& s01 = p[1];
  const PixelSample& s10 = p[w];
  const PixelSample& s11 = p[w + 1];
  depth_ok = s00[3] > 0 && s01[3] > 0 && s10[3] > 0 && s11[3] > 0;
  return (1 - ay) * ((1 - ax) * s00 + ax * s01) + ay * ((1 - ax) * s10 + ax * s11);
}

// The residuals of the reference's `points` (x, y, z, intensity) moved by (R, t) into `level`,
// each with its Jacobian rows; every 4th point's absolute residuals go to abs_i and abs_z (for
// the robust scales). With `quadratic_noise`, depth residuals and their rows are divided by z^2.
void residualsAt(const AlignmentReference::Points& points, const PyramidLevel& level,
                 const Eigen::Matrix3f& R, const Eigen::Vector3f& t, bool quadratic_noise,
                 std::vector<Residual>& residuals, std::vector<float>& abs_i,
                 std::vector<float>& abs_z) {
  const LevelCamera& c = level.camera;
  const float umax = static_cast<float>(c.width - 2), vmax = static_cast<float>(c.height - 2);
  for (std::size_t n = 0; n < points.size(); ++n) {
    const Eigen::Vector4f& q = points[n];
    const Eigen::Vector3f p = R * q.head<3>() + t;
    if (p.z() <= 0.05f) continue;
    const float iz = 1.0f / p.z();
    const float u = c.fx * p.x() * iz + c.cx, v = c.fy * p.y() * iz + c.cy;
    if (!(u >= 1.0f && v >= 1.0f && u < umax && v < vmax)) continue;
    bool depth_ok = false;
    const PixelSample s = bilinear(level, u, v, depth_ok);
    // d(u,v)/dp rows: (fx/z, 0, -fx x/z^2), (0, fy/z, -fy y/z^2).
    const float dux = c.fx * iz, dvy = c.fy * iz;
    const float duz = -c.fx * p.x() * iz * iz, dvz = -c.fy * p.y() * iz * iz;
    Residual r;
    r.ji = jacobianRow(p, s[1] * dux, s[2] * dvy, s[1] * duz + s[2] * dvz);
    r.ri = s[0] - q[3];
    if (depth_ok) {
      r.jz = jacobianRow(p, s[4] * dux, s[5] * dvy, s[4] * duz + s[5] * dvz - 1.0f);
      r.rz = s[3] - p.z();
      if (quadratic_noise) {
        // In units of the pixel's own noise: a structured-light sensor's grows with z^2, so a
        // far pixel's metre of residual says less than a near one's.
        const float n = 1.0f / (p.z() * p.z());
        r.jz *= n;
        r.rz *= n;
      }
      if ((n & 3) == 0) abs_z.push_back(std::abs(r.rz));
    } else {
      r.rz = std::numeric_limits<float>::quiet_NaN();
    }
    if ((n & 3) == 0) abs_i.push_back(std::abs(r.ri));
    residuals.push_back(r);
  }
}

// The Gauss-Newton normal equations H dx = -b of the residuals, Huber-weighted with the robust
// scales 1/inv_i and 1/inv_z (depth residuals weighed `depth_weight` against intensity ones).
void normalEquations(const std::vector<Residual>& residuals, float inv_i, float inv_z, float k,
                     float depth_weight, Matrix6d& H, Vector6d& b) {
  Eigen::Matrix<float, 6, 6> Hf = Eigen::Matrix<float, 6, 6>::Zero();
  Vector6f bf = Vector6f::Zero();
  H.setZero();
  b.setZero();
  std::size_t batch = 0;
  for (const Residual& r : residuals) {
    const float ni = r.ri * inv_i;
    const float wi = huberWeight(ni, k) * inv_i * inv_i;
    Hf.noalias() += (wi * r.ji) * r.ji.transpose();
    bf.noalias() += (wi * r.ri) * r.ji;
    if (r.rz == r.rz) {
      const float nz = r.rz * inv_z;
      const float wz = depth_weight * huberWeight(nz, k) * inv_z * inv_z;
      Hf.noalias() += (wz * r.jz) * r.jz.transpose();
      bf.noalias() += (wz * r.rz) * r.jz;
    }
    // Flush to double now and then: float sums of tens of thousands of terms lose digits.
    if (++batch == 512) {
      H += Hf.cast<double>();
      b += bf.cast<double>();
      Hf.setZero();
      bf.setZero();
      batch = 0;
    }
  }
  H += Hf.cast<double>();
  b += bf.cast<double>();
}

}  // namespace

void AlignmentReference::build(const ImagePyramid& pyramid, int finest, int coarsest,
                               float min_gradient) {
  levels.resize(static_cast<std::size_t>(coarsest + 1));
  valid_pixels = 0;
  for (int l = finest; l <= coarsest; ++l) {
    const PyramidLevel& source = pyramid.level(l);
    Level& out = levels[static_cast<std::size_t>(l)];
    out.camera = source.camera;
    out.points.clear();
    const LevelCamera& c = source.camera;
    const float min_g2 = min_gradient * min_gradient;
    // A border of 2 pixels: a point's sampled neighbours need their own neighbours.
    for (int y = 2; y + 2 < c.height; ++y) {
      const float* z = source.depth.ptr<float>(y);
      const float* g = source.gray.ptr<float>(y);
      const float* gu = source.gray.ptr<float>(y - 1);
      const float* gd = source.gray.ptr<float>(y + 1);
      for (int x = 2; x + 2 < c.width; ++x) {
        if (z[x] <= 0) continue;
        if (l == finest) {
          ++valid_pixels;
          const float gx = 0.5f * (g[x + 1] - g[x - 1]), gy = 0.5f * (gd[x] - gu[x]);
          if (gx * gx + gy * gy < min_g2 && ((x | y) & 1)) continue;
        }
        const float px = (static_cast<float>(x) - c.cx) / c.fx * z[x];
        const float py = (static_cast<float>(y) - c.cy) / c.fy * z[x];
        out.points.emplace_back(px, py, z[x], g[x]);
      }
    }
  }
}

AlignmentResult DenseAligner::align(const AlignmentReference& reference,
                                    const ImagePyramid& current, const Eigen::Isometry3d& guess) {
  AlignmentResult result;
  Eigen::Isometry3d motion = guess;
  const int finest = options_.finest_level;
  const int coarsest = std::min(options_.coarsest_level, current.levels() - 1);
  const float k = static_cast<float>(options_.huber_k);
  const float depth_weight = static_cast<float>(options_.depth_weight);
  const bool quadratic_noise = options_.depth_noise == "quadratic";
  std::vector<Residual>& residuals = residuals_;
  std::vector<float>& abs_i = abs_i_;
  std::vector<float>& abs_z = abs_z_;
  float sigma_i = 10.0f, sigma_z = 0.02f;

  for (int l = coarsest; l >= finest; --l) {
    const auto& points = reference.levels[static_cast<std::size_t>(l)].points;
    const PyramidLevel& level = current.level(l);
    const int iterations = l == finest ? options_.finest_iterations : options_.max_iterations;
    residuals.reserve(points.size());
    std::size_t landed = 0;
    Matrix6d H = Matrix6d::Zero();
    for (int it = 0; it < iterations; ++it) {
      const Eigen::Matrix3f R = motion.linear().cast<float>();
      const Eigen::Vector3f t = motion.translation().cast<float>();
      residuals.clear();
      abs_i.clear();
      abs_z.clear();
      residualsAt(points, level, R, t, quadratic_noise, residuals, abs_i, abs_z);
      landed = residuals.size();
      if (landed < 12) break;
      sigma_i = robustSigma(abs_i, sigma_i);
      sigma_z = robustSigma(abs_z, sigma_z);
      Vector6d b;
      normalEquations(residuals, 1.0f / sigma_i, 1.0f / sigma_z, k, depth_weight, H, b);
      const Vector6d step = H.ldlt().solve(-b);
      if (!step.allFinite()) break;
      motion = expSE3(step) * motion;
      if (step.head<3>().norm() < 1e-5 && step.tail<3>().norm() < 1e-5) break;
    }
    if (l == finest) {
      result.overlap =
          points.empty() ? 0.0 : static_cast<double>(landed) / static_cast<double>(points.size());
      result.intensity_sigma = sigma_i;
      if (landed > 0) {
        result.information = H / static_cast<double>(landed);
        Eigen::SelfAdjointEigenSolver<Matrix6d> eig(result.information, Eigen::EigenvaluesOnly);
        result.min_information = eig.eigenvalues()(0);
      }
    }
  }
  result.motion = motion;
  result.finite = motion.matrix().allFinite();
  return result;
}

}  // namespace rgbdmap
