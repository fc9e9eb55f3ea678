#include "rgbdmap/tracking/dense_aligner.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstring>

#include "rgbdmap/base/vector_clones.hpp"
#include "rgbdmap/tracking/twist.hpp"

namespace rgbdmap {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

using Residuals = DenseAligner::Residuals;

// The 8 lanes the normal equations are summed in (GCC's vector extension: one AVX register in
// the x86-64-v3 clone, two SSE ones in the baseline).
constexpr std::size_t kLanes = 8;
using Lanes = float __attribute__((vector_size(4 * kLanes)));

std::size_t roundUpToLanes(std::size_t n) { return (n + kLanes - 1) / kLanes * kLanes; }

// (Vectors pass by reference: by value, the baseline and the AVX clone would disagree on how.)
[[gnu::always_inline]] inline void load(Lanes& v, const float* p) { std::memcpy(&v, p, sizeof(v)); }

[[gnu::always_inline]] inline float laneSum(const Lanes& v) {
  float s = 0;
  for (std::size_t i = 0; i < kLanes; ++i) s += v[i];
  return s;
}

// Stores the Jacobian row of a residual whose gradient with respect to the warped point p is g,
// (g, p x g) for a left increment (translation, rotation), at row m of the columns j.
inline void storeJacobianRow(std::vector<float> (&j)[6], std::size_t m, const Eigen::Vector3f& p,
                             float gx, float gy, float gz) {
  j[0][m] = gx;
  j[1][m] = gy;
  j[2][m] = gz;
  j[3][m] = p.y() * gz - p.z() * gy;
  j[4][m] = p.z() * gx - p.x() * gz;
  j[5][m] = p.x() * gy - p.y() * gx;
}

// Robust spread (1.4826 * median absolute value) of every 4th value, which is plenty.
float robustSigma(std::vector<float>& values, float fallback) {
  if (values.size() < 16) return fallback;
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return std::max(1.4826f * *mid, 1e-6f);
}

// Bilinear lookup of all sampled quantities at (u, v); false when a depth corner is missing
// (then only the intensity part, which is never missing, is valid: depth fields are zeroed).
[[gnu::always_inline]] inline PixelSample bilinear(const PyramidLevel& level, float u, float v,
                                                   bool& depth_ok) {
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

// When the row a point at height y_over_z (y / z) lands on was read, in readouts after the middle
// row (-1/2 .. 1/2; `inv_height`: 1 / the image's rows).
[[gnu::always_inline]] inline float readoutShare(const LevelCamera& c, float inv_height,
                                                 float y_over_z) {
  return (c.fy * y_over_z + c.cy) * inv_height - 0.5f;
}

// The residuals of the reference's `points` (x, y, z, intensity) moved by (R, t) into `level`,
// each with its Jacobian rows; every 4th point's absolute residuals go to abs_i and abs_z (for
// the robust scales). With `quadratic_noise`, depth residuals and their rows are divided by z^2.
// With `inv_knee2` (1 / knee^2, or 0), intensity residuals and their rows are divided by
// sqrt(1 + |gradient|^2 / knee^2): about knee / |gradient| where the image is steeper than knee.
// With a rolling shutter (`readout` not zero), a point is looked up where the camera was when
// the row it lands on was read (to first order: the motion over one readout is small).
RGBDMAP_VECTOR_CLONES void residualsAt(const AlignmentReference::Points& points,
                                       const PyramidLevel& level, const Eigen::Matrix3f& R,
                                       const Eigen::Vector3f& t, bool quadratic_noise,
                                       float inv_knee2, const ReadoutMotion& readout,
                                       Residuals& out, std::vector<float>& abs_i,
                                       std::vector<float>& abs_z) {
  const bool rolling = !readout.isZero();
  const Eigen::Vector3f w = readout.head<3>(), dt = readout.tail<3>();
  const LevelCamera& c = level.camera;
  const float inv_height = 1.0f / static_cast<float>(c.height);
  const float umax = static_cast<float>(c.width - 2), vmax = static_cast<float>(c.height - 2);
  out.reset(points.size());
  std::size_t m = 0;
  for (std::size_t n = 0; n < points.size(); ++n) {
    const Eigen::Vector4f& q = points[n];
    Eigen::Vector3f p = R * q.head<3>() + t;
    if (p.z() <= 0.05f) continue;
    float iz = 1.0f / p.z();
    if (rolling) {
      const float s = readoutShare(c, inv_height, p.y() * iz);
      const Eigen::Vector3f shift = s * (w.cross(p) + dt);
      p -= shift;
      iz *= 1.0f + shift.z() * iz;  // 1 / (z - dz) to first order: dz is a fraction of a mm
    }
    const float u = c.fx * p.x() * iz + c.cx, v = c.fy * p.y() * iz + c.cy;
    if (!(u >= 1.0f && v >= 1.0f && u < umax && v < vmax)) continue;
    bool depth_ok = false;
    const PixelSample s = bilinear(level, u, v, depth_ok);
    // d(u,v)/dp rows: (fx/z, 0, -fx x/z^2), (0, fy/z, -fy y/z^2).
    const float dux = c.fx * iz, dvy = c.fy * iz;
    const float duz = -c.fx * p.x() * iz * iz, dvz = -c.fy * p.y() * iz * iz;
    const float gi =
        inv_knee2 > 0 ? 1.0f / std::sqrt(1.0f + inv_knee2 * (s[1] * s[1] + s[2] * s[2])) : 1.0f;
    const float gx = gi * s[1], gy = gi * s[2];
    storeJacobianRow(out.ji, m, p, gx * dux, gy * dvy, gx * duz + gy * dvz);
    out.ri[m] = gi * (s[0] - q[3]);
    if (depth_ok) {
      // In units of the pixel's own noise with `quadratic_noise`: a structured-light sensor's
      // grows with z^2, so a far pixel's metre of residual says less than a near one's.
      const float scale = quadratic_noise ? 1.0f / (p.z() * p.z()) : 1.0f;
      storeJacobianRow(out.jz, m, p, scale * s[4] * dux, scale * s[5] * dvy,
                       scale * (s[4] * duz + s[5] * dvz - 1.0f));
      out.rz[m] = scale * (s[3] - p.z());
      out.has_z[m] = 1.0f;
      if ((n & 3) == 0) abs_z.push_back(std::abs(out.rz[m]));
    } else {
      for (auto& column : out.jz) column[m] = 0.0f;
      out.rz[m] = 0.0f;
      out.has_z[m] = 0.0f;
    }
    out.source[m] = static_cast<std::uint32_t>(n);
    if ((n & 3) == 0) abs_i.push_back(std::abs(out.ri[m]));
    ++m;
  }
  out.size = m;
  out.padToLanes();
}

// The frame's brightness change against the reference (auto-exposure), as one offset in grey
// levels: the Huber-weighted mean of the intensity residuals (weighed by their distance from the
// last estimate `offset`), shrunk towards zero by `tolerance`: an offset of a few grey levels is
// as likely a misalignment or the scene's own content as an exposure change. Subtracts it from
// every residual and refills `abs_i` (every 4th, as residualsAt does) with what remains.
// Returns the new estimate.
float subtractOffset(Residuals& r, float offset, float sigma_i, float k, float tolerance,
                     std::vector<float>& abs_i) {
  const float inv = 1.0f / sigma_i;
  double sw = 0, swr = 0;
  for (std::size_t m = 0; m < r.size; ++m) {
    const float w = 1.0f / std::max(std::abs((r.ri[m] - offset) * inv), k);
    sw += w;
    swr += w * r.ri[m];
  }
  const float mean = static_cast<float>(swr / sw);
  offset = std::copysign(std::max(0.0f, std::abs(mean) - tolerance), mean);
  abs_i.clear();
  for (std::size_t m = 0; m < r.size; ++m) {
    r.ri[m] -= offset;
    if ((m & 3) == 0) abs_i.push_back(std::abs(r.ri[m]));
  }
  return offset;
}

// Adds the weighted products of the columns a[first..5] and r (a[6]), 8 rows at a time, to
// rows first..last of H's upper triangle (sum of w a_i a_j) and of b (sum of w a_i r): few
// enough sums a pass for them and the columns to stay in registers.
template <int kFirst, int kLast>
[[gnu::always_inline]] inline void addProducts(const float* w, const float* const (&a)[7],
                                               std::size_t rows, Matrix6d& H, Vector6d& b) {
  Lanes sums[kLast - kFirst + 1][7] = {};
  for (std::size_t m = 0; m < rows; m += kLanes) {
    Lanes weight, col[7];
    load(weight, w + m);
    for (int c = kFirst; c < 7; ++c) load(col[c], a[c] + m);
    for (int i = kFirst; i <= kLast; ++i) {
      const Lanes wa = weight * col[i];
      for (int j = i; j < 7; ++j) sums[i - kFirst][j] += wa * col[j];
    }
  }
  for (int i = kFirst; i <= kLast; ++i) {
    for (int j = i; j < 6; ++j) H(i, j) += laneSum(sums[i - kFirst][j]);
    b(i) += laneSum(sums[i - kFirst][6]);
  }
}

// Adds rows begin..begin+n of the Jacobian columns j and the residuals res, weighted by w[0..n),
// to H and b. (Inlined, not a lambda: a lambda would be compiled for the baseline only, outside
// the caller's x86-64-v3 clone.)
[[gnu::always_inline]] inline void addRows(const std::vector<float> (&j)[6],
                                           const std::vector<float>& res, const float* w,
                                           std::size_t begin, std::size_t n, Matrix6d& H,
                                           Vector6d& b) {
  const float* const a[7] = {j[0].data() + begin, j[1].data() + begin, j[2].data() + begin,
                             j[3].data() + begin, j[4].data() + begin, j[5].data() + begin,
                             res.data() + begin};
  addProducts<0, 0>(w, a, n, H, b);
  addProducts<1, 1>(w, a, n, H, b);
  addProducts<2, 3>(w, a, n, H, b);
  addProducts<4, 5>(w, a, n, H, b);
}

// Huber weights divided by the squared scale: k / max(|r| / sigma, k) / sigma^2, 1 / sigma^2
// within k sigma (written without a branch, so that the loop is vectorised). `valid` (1 or 0),
// when given, keeps only the rows that have a residual.
RGBDMAP_VECTOR_CLONES void huberWeights(const float* residuals, const float* valid, std::size_t n,
                                        float inv_sigma, float k, float scale, float* out) {
  const float c = scale * k * inv_sigma * inv_sigma;
  for (std::size_t m = 0; m < n; ++m)
    out[m] = (valid ? valid[m] : 1.0f) * c / std::max(std::abs(residuals[m] * inv_sigma), k);
}

// The Gauss-Newton normal equations H dx = -b of the residuals, Huber-weighted with the robust
// scales 1/inv_i and 1/inv_z (depth residuals weighed `depth_weight` against intensity ones).
// Only H's upper triangle is summed, 8 rows at a time, in float over chunks of 512 residuals
// and in double across them (float sums of tens of thousands of terms lose digits).
RGBDMAP_VECTOR_CLONES void normalEquations(const Residuals& r, float inv_i, float inv_z, float k,
                                           float depth_weight, Matrix6d& H, Vector6d& b) {
  constexpr std::size_t kChunk = 512;
  H.setZero();
  b.setZero();
  alignas(32) float wi[kChunk], wz[kChunk];
  for (std::size_t begin = 0; begin < r.size; begin += kChunk) {
    // The columns are padded with zeros to whole lanes.
    const std::size_t n = roundUpToLanes(std::min(r.size - begin, kChunk));
    huberWeights(r.ri.data() + begin, nullptr, n, inv_i, k, 1.0f, wi);
    huberWeights(r.rz.data() + begin, r.has_z.data() + begin, n, inv_z, k, depth_weight, wz);
    addRows(r.ji, r.ri, wi, begin, n, H, b);  // the intensity rows
    addRows(r.jz, r.rz, wz, begin, n, H, b);  // the depth rows
  }
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < i; ++j) H(i, j) = H(j, i);
}

// The residuals' derivatives with respect to the readout time (ai, az), at the motion (R, t)
// they were computed at: a longer readout moves the reference's point along its camera's motion
// (its row's share of it) and the lookup in the frame against the frame's. `frame` and
// `reference`: each camera's motion per second (rotation vector, translation).
RGBDMAP_VECTOR_CLONES void readoutDerivatives(const AlignmentReference::Points& points,
                                              const LevelCamera& c, const Eigen::Matrix3f& R,
                                              const Eigen::Vector3f& t, const ReadoutMotion& frame,
                                              const ReadoutMotion& reference, Residuals& r) {
  const Eigen::Vector3f fw = frame.head<3>(), fv = frame.tail<3>();
  const Eigen::Vector3f rw = reference.head<3>(), rv = reference.tail<3>();
  const float inv_height = 1.0f / static_cast<float>(c.height);
  for (std::size_t m = 0; m < r.size; ++m) {
    const Eigen::Vector3f q = points[r.source[m]].head<3>();
    const Eigen::Vector3f p = R * q + t;
    const float sq = readoutShare(c, inv_height, q.y() / q.z());
    const float sp = readoutShare(c, inv_height, p.y() / p.z());
    const Eigen::Vector3f dp = R * (sq * (rw.cross(q) + rv)) - sp * (fw.cross(p) + fv);
    r.ai[m] = r.ji[0][m] * dp.x() + r.ji[1][m] * dp.y() + r.ji[2][m] * dp.z();
    r.az[m] = r.jz[0][m] * dp.x() + r.jz[1][m] * dp.y() + r.jz[2][m] * dp.z();
  }
  r.padToLanes();
}

// The readout's row of the normal equations beside the motion's, weighted as normalEquations
// weighs: h = sum of w a J, hh = sum of w a^2, g = sum of w a r, for the derivatives a (ai, az).
// Summed 8 rows at a time in float within chunks of 512, in double across them.
RGBDMAP_VECTOR_CLONES void readoutRow(const Residuals& r, float inv_i, float inv_z, float k,
                                      float depth_weight, Vector6d& h, double& hh, double& g) {
  constexpr std::size_t kChunk = 512;
  h.setZero();
  hh = g = 0;
  alignas(32) float wi[kChunk], wz[kChunk];
  for (std::size_t begin = 0; begin < r.size; begin += kChunk) {
    const std::size_t n = roundUpToLanes(std::min(r.size - begin, kChunk));
    huberWeights(r.ri.data() + begin, nullptr, n, inv_i, k, 1.0f, wi);
    huberWeights(r.rz.data() + begin, r.has_z.data() + begin, n, inv_z, k, depth_weight, wz);
    Lanes sums[8] = {};
    for (std::size_t m = 0; m < n; m += kLanes) {
      Lanes w, a, c, wai, waz;
      load(w, wi + m);
      load(a, r.ai.data() + begin + m);
      wai = w * a;
      sums[6] += wai * a;
      load(w, wz + m);
      load(a, r.az.data() + begin + m);
      waz = w * a;
      sums[6] += waz * a;
      for (int j = 0; j < 6; ++j) {
        load(c, r.ji[j].data() + begin + m);
        sums[j] += wai * c;
        load(c, r.jz[j].data() + begin + m);
        sums[j] += waz * c;
      }
      load(c, r.ri.data() + begin + m);
      sums[7] += wai * c;
      load(c, r.rz.data() + begin + m);
      sums[7] += waz * c;
    }
    for (int j = 0; j < 6; ++j) h(j) += laneSum(sums[j]);
    hh += laneSum(sums[6]);
    g += laneSum(sums[7]);
  }
}

}  // namespace

std::array<std::vector<float>*, 17> DenseAligner::Residuals::columns() {
  return {&ji[0], &ji[1], &ji[2], &ji[3], &ji[4], &ji[5], &jz[0], &jz[1], &jz[2],
          &jz[3], &jz[4], &jz[5], &ri,    &rz,    &has_z, &ai,    &az};
}

void DenseAligner::Residuals::reset(std::size_t capacity) {
  const std::size_t padded = roundUpToLanes(capacity);
  for (std::vector<float>* column : columns())
    if (column->size() < padded) column->resize(padded);
  if (source.size() < padded) source.resize(padded);
  size = 0;
}

void DenseAligner::Residuals::padToLanes() {
  for (std::vector<float>* column : columns())
    std::fill(column->begin() + size, column->begin() + roundUpToLanes(size), 0.0f);
}

void AlignmentReference::build(const ImagePyramid& pyramid, int finest, int coarsest,
                               float min_gradient, const ReadoutMotion& readout) {
  const Eigen::Vector3f w = readout.head<3>(), dt = readout.tail<3>();
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
      // Seen from the camera at mid-readout: this row was read s readouts after it.
      const float s = static_cast<float>(y) / static_cast<float>(c.height) - 0.5f;
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
        const Eigen::Vector3f p(px, py, z[x]);
        const Eigen::Vector3f mid = p + s * (w.cross(p) + dt);
        out.points.emplace_back(mid.x(), mid.y(), mid.z(), g[x]);
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
  const float knee = static_cast<float>(options_.coarse_gradient_knee);
  const float coarse_inv_knee2 = knee > 0 ? 1.0f / (knee * knee) : 0.0f;
  Residuals& residuals = residuals_;
  std::vector<float>& abs_i = abs_i_;
  std::vector<float>& abs_z = abs_z_;
  float sigma_i = 10.0f, sigma_z = 0.02f;
  const bool brightness_offset = options_.brightness == "offset";
  const float brightness_tolerance = static_cast<float>(options_.brightness_tolerance);
  float offset = 0.0f;
  const bool estimate_readout = !readout_rate_.isZero();

  for (int l = coarsest; l >= finest; --l) {
    const auto& points = reference.levels[static_cast<std::size_t>(l)].points;
    const PyramidLevel& level = current.level(l);
    const int iterations = l == finest ? options_.finest_iterations : options_.max_iterations;
    std::size_t landed = 0;
    Matrix6d H = Matrix6d::Zero();
    Vector6d b = Vector6d::Zero();
    Eigen::Matrix3f R;  // the motion the last residuals were computed at
    Eigen::Vector3f t;
    for (int it = 0; it < iterations; ++it) {
      R = motion.linear().cast<float>();
      t = motion.translation().cast<float>();
      abs_i.clear();
      abs_z.clear();
      residualsAt(points, level, R, t, quadratic_noise, l == finest ? 0.0f : coarse_inv_knee2,
                  readout_, residuals, abs_i, abs_z);
      landed = residuals.size;
      if (landed < 12) break;
      // On the finest level only: while coarse levels bring the frame into place, a misalignment
      // shifts the mean residual as much as an exposure change does.
      if (brightness_offset && l == finest)
        offset = subtractOffset(residuals, offset, sigma_i, k, brightness_tolerance, abs_i);
      sigma_i = robustSigma(abs_i, sigma_i);
      sigma_z = robustSigma(abs_z, sigma_z);
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
      if (estimate_readout && landed >= 12) {
        // Given the motion at its optimum (b is almost zero there), what the readout adds: the
        // readout's equation once the motion's is eliminated (Schur complement).
        readoutDerivatives(points, level.camera, R, t, readout_rate_, reference.readout_rate,
                           residuals);
        Vector6d h;
        double hh, g;
        readoutRow(residuals, 1.0f / sigma_i, 1.0f / sigma_z, k, depth_weight, h, hh, g);
        const auto ldlt = H.ldlt();
        const double information = hh - h.dot(ldlt.solve(h));
        if (information > 0 && std::isfinite(information)) {
          result.readout_information = information;
          result.readout_step = -(g - h.dot(ldlt.solve(b))) / information;
        }
      }
    }
  }
  result.motion = motion;
  result.finite = motion.matrix().allFinite();
  return result;
}

}  // namespace rgbdmap
