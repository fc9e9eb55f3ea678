#include "rgbdmap/mapping/tsdf_integrator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

#include "rgbdmap/base/vector_clones.hpp"
#include "rgbdmap/mapping/back_projector.hpp"

namespace rgbdmap {

namespace {

// Rows of cells per task when incidence is computed, blocks per task when voxels are updated:
// enough work per task that handing tasks out costs nothing, enough tasks that threads finish
// together.
constexpr int kCellRowsPerTask = 8;
constexpr std::size_t kBlocksPerTask = 32;
constexpr int kAllocationRowsPerTask = 32;
constexpr std::size_t kScanBlocksPerTask = 4096;
constexpr std::size_t kRecentBlocks = 1024;  // a power of 2

// Whether any lane of a vector comparison's result is set: its bytes as 64-bit words, OR-ed
// (a test of the whole register, where lane by lane would move each lane out of it).
template <typename Mask>
inline bool anyOf(const Mask& mask) {
  static_assert(sizeof(Mask) % sizeof(std::uint64_t) == 0, "a mask is whole 64-bit words");
  std::uint64_t words[sizeof(Mask) / sizeof(std::uint64_t)];
  std::memcpy(words, &mask, sizeof(Mask));
  std::uint64_t any = 0;
  for (const std::uint64_t word : words) any |= word;
  return any != 0;
}

// The image itself when its rows are contiguous, else a contiguous copy kept in `copy`.
const cv::Mat& contiguous(const cv::Mat& image, cv::Mat& copy) {
  if (image.isContinuous()) return image;
  image.copyTo(copy);
  return copy;
}

}  // namespace

// Allocates the blocks along each sampled pixel's ray within the band around its depth. The rays
// are walked on the pool, a band of rows per task, each task listing the blocks it crossed; the
// lists are then entered in task order, so blocks are created in the same order whatever the
// thread count.
void TsdfIntegrator::allocate(const cv::Mat& depth, const Eigen::Isometry3d& pose, VoxelMap& map,
                              WorkerPool* pool) {
  const CameraIntrinsics& cam = camera;
  const float block = static_cast<float>(map.voxelSize() * VoxelMap::kBlockEdge);
  const float inv_block = 1.0f / block;
  const Eigen::Matrix3f R = pose.linear().cast<float>();
  const Eigen::Vector3f t = pose.translation().cast<float>();
  const int stride = std::max(1, allocation_stride);
  const int rows_per_task = stride * std::max(1, kAllocationRowsPerTask / stride);
  const std::size_t tasks =
      static_cast<std::size_t>((depth.rows + rows_per_task - 1) / rows_per_task);
  crossed_.resize(std::max(crossed_.size(), tasks));
  auto walk = [&](std::size_t task) {
    std::vector<Eigen::Vector3i>& crossed = crossed_[task];
    crossed.clear();
    // The blocks this task listed last, by a hash of their coordinates: neighbouring rays cross
    // the same few blocks, and each repeat would cost the map a lookup in its hash table and a
    // cache miss on the block. Skipping a repeat changes nothing: the map enters a block once.
    std::array<Eigen::Vector3i, kRecentBlocks> recent;
    recent.fill(Eigen::Vector3i::Constant(INT32_MIN));
    const int first_row = static_cast<int>(task) * rows_per_task;
    const int last_row = std::min(depth.rows, first_row + rows_per_task);
    for (int v = first_row; v < last_row; v += stride) {
      const float* row = depth.ptr<float>(v);
      for (int u = 0; u < depth.cols; u += stride) {
        const float d = row[u];
        if (!(d > 0.0f)) continue;
        const float band = bandAt(d);
        const Eigen::Vector3f ray =
            R * Eigen::Vector3f(static_cast<float>((u - cam.cx) / cam.fx),
                                static_cast<float>((v - cam.cy) / cam.fy), 1.0f);
        // Steps of at most half a block along the ray, so that no block it crosses is skipped.
        const int steps =
            1 + static_cast<int>(std::ceil(2.0f * band * ray.norm() / (0.5f * block)));
        for (int i = 0; i <= steps; ++i) {
          const float s =
              d - band + 2.0f * band * static_cast<float>(i) / static_cast<float>(steps);
          const Eigen::Vector3f p = (t + ray * s) * inv_block;
          const Eigen::Vector3i b(static_cast<int>(std::floor(p.x())),
                                  static_cast<int>(std::floor(p.y())),
                                  static_cast<int>(std::floor(p.z())));
          Eigen::Vector3i& seen = recent[(static_cast<std::uint32_t>(b.x()) * 73856093u ^
                                          static_cast<std::uint32_t>(b.y()) * 19349663u ^
                                          static_cast<std::uint32_t>(b.z()) * 83492791u) &
                                         (kRecentBlocks - 1)];
          if (seen == b) continue;
          seen = b;
          crossed.push_back(b);
        }
      }
    }
  };
  runTasks(pool, tasks, walk);
  for (std::size_t task = 0; task < tasks; ++task)
    for (const Eigen::Vector3i& b : crossed_[task]) map.touchBlock(b);
}

// Adds the blocks already in the map that a view sees through: between the camera and what it
// measured, beyond its band (in distance to the surface). Allocation only reaches the band around
// each measurement, so without this an object that went away would never be updated again. Scans
// the blocks' coordinates (a compact array), not the blocks, in chunks on the pool; the chunks'
// finds are added in order.
void TsdfIntegrator::touchSeenThrough(const cv::Mat& depth,
                                      const Eigen::Isometry3f& world_to_camera, VoxelMap& map,
                                      WorkerPool* pool) {
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx) + 0.5f, cy = static_cast<float>(camera.cy) + 0.5f;
  const float edge = static_cast<float>(map.voxelSize() * VoxelMap::kBlockEdge);
  const float half_diagonal = 0.5f * std::sqrt(3.0f) * edge;
  const auto seenThrough = [&](const Eigen::Vector3i& block) {
    const Eigen::Vector3f c =
        world_to_camera * ((block.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * edge);
    if (c.z() <= 0.0f) return false;
    const float u = fx * c.x() / c.z() + cx, v = fy * c.y() / c.z() + cy;
    if (!(u >= 0.0f && v >= 0.0f && u < static_cast<float>(depth.cols) &&
          v < static_cast<float>(depth.rows)))
      return false;
    const int ui = static_cast<int>(u), vi = static_cast<int>(v);
    const float d = depth.ptr<float>(vi)[ui];
    return d > 0.0f && (d - c.z() + half_diagonal) * incidenceAt(ui, vi) >= bandAt(d);
  };
  const std::vector<Eigen::Vector3i>& coordinates = map.blockCoordinates();
  const std::size_t tasks = (coordinates.size() + kScanBlocksPerTask - 1) / kScanBlocksPerTask;
  seen_through_.resize(std::max(seen_through_.size(), tasks));
  auto scan = [&](std::size_t task) {
    std::vector<std::uint32_t>& found = seen_through_[task];
    found.clear();
    const std::size_t first = task * kScanBlocksPerTask;
    const std::size_t last = std::min(coordinates.size(), first + kScanBlocksPerTask);
    for (std::size_t i = first; i < last; ++i)
      if (coordinates[i] != VoxelMap::kNoBlock && seenThrough(coordinates[i]))
        found.push_back(static_cast<std::uint32_t>(i));
  };
  runTasks(pool, tasks, scan);
  // Blocks on disk (VoxelMap::keepWithin) within the depth seen come back if seen through. Found
  // before any is touched: touching a block brings its neighbours back from disk.
  std::vector<Eigen::Vector3i> stored_through;
  if (!map.storedBlocks().empty()) {
    float farthest = 0.0f;
    for (int v = 0; v < depth.rows; ++v) {
      const float* row = depth.ptr<float>(v);
      for (int u = 0; u < depth.cols; ++u) farthest = std::max(farthest, row[u]);
    }
    // Depth is along the optical axis: a ray to the image's corner is longer.
    const float corner_x = std::max(cx, static_cast<float>(depth.cols) - cx) / fx;
    const float corner_y = std::max(cy, static_cast<float>(depth.rows) - cy) / fy;
    const float reach =
        farthest * std::sqrt(1.0f + corner_x * corner_x + corner_y * corner_y) + half_diagonal;
    const Eigen::Vector3f centre = world_to_camera.inverse().translation();
    for (const Eigen::Vector3i& b : map.storedNear(centre, reach))
      if (seenThrough(b)) stored_through.push_back(b);
  }
  for (std::size_t task = 0; task < tasks; ++task)
    for (const std::uint32_t i : seen_through_[task]) map.touchExisting(i);
  for (const Eigen::Vector3i& b : stored_through) map.touchBlock(b);
}

void TsdfIntegrator::prepareIncidence(const cv::Mat& depth, WorkerPool* pool) {
  const int width = depth.cols, height = depth.rows;
  const float min_cos = static_cast<float>(std::clamp(min_incidence_cosine, 1e-3, 1.0));

  // Incidence varies slowly across a surface, so it is taken on a grid of cells of cell x cell
  // pixels: the depth averaged over each cell (holes left out) and the normal from the cells on
  // either side. Averaging matters: a single pixel's noise at 3 m (sigma 1.4 cm, twice the pixel
  // spacing) would make every surface look seen head-on.
  cell_bits_ = 0;  // the largest power of two not above normal_cell
  while ((2 << cell_bits_) <= normal_cell) ++cell_bits_;
  const int cell = 1 << cell_bits_;
  grid_width_ = (width + cell - 1) / cell;
  grid_height_ = (height + cell - 1) / cell;
  const std::size_t cells = static_cast<std::size_t>(grid_width_) * grid_height_;
  cosine_.resize(cells);

  const std::size_t tasks =
      static_cast<std::size_t>((grid_height_ + kCellRowsPerTask - 1) / kCellRowsPerTask);
  cell_point_.resize(cells);
  column_sums_.resize(tasks * 2 * static_cast<std::size_t>(width));
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  // Each cell's point: the camera-frame point at its centre at its mean depth (holes left out),
  // or a NaN depth where a quarter of the cell or less holds depth. The pixels are summed down
  // the cell's rows first (a loop along the row, vectorised), then across its columns.
  runTasks(pool, tasks, [&](std::size_t task) {
    float* depth_sum = column_sums_.data() + task * 2 * static_cast<std::size_t>(width);
    float* count = depth_sum + width;
    const int first = static_cast<int>(task) * kCellRowsPerTask;
    const int last = std::min(grid_height_, first + kCellRowsPerTask);
    for (int j = first; j < last; ++j) {
      std::fill(depth_sum, depth_sum + width, 0.0f);
      std::fill(count, count + width, 0.0f);
      const int rows = std::min(cell, height - j * cell);
      for (int v = j * cell; v < j * cell + rows; ++v) {
        const float* in = depth.ptr<float>(v);
        for (int u = 0; u < width; ++u) {
          const bool measured = in[u] > 0.0f;
          depth_sum[u] += measured ? in[u] : 0.0f;
          count[u] += measured ? 1.0f : 0.0f;
        }
      }
      Eigen::Vector3f* points = cell_point_.data() + static_cast<std::size_t>(j) * grid_width_;
      for (int i = 0; i < grid_width_; ++i) {
        const int columns = std::min(cell, width - i * cell);
        float sum = 0.0f, pixels = 0.0f;
        for (int u = i * cell; u < i * cell + columns; ++u) {
          sum += depth_sum[u];
          pixels += count[u];
        }
        if (4.0f * pixels < static_cast<float>(rows * columns) || !(pixels > 0.0f)) {
          points[i] = Eigen::Vector3f(0.0f, 0.0f, std::numeric_limits<float>::quiet_NaN());
          continue;
        }
        const float d = sum / pixels;
        const float u = (static_cast<float>(i) + 0.5f) * static_cast<float>(cell) - 0.5f;
        const float v = (static_cast<float>(j) + 0.5f) * static_cast<float>(cell) - 0.5f;
        points[i] = Eigen::Vector3f((u - cx) / fx * d, (v - cy) / fy * d, d);
      }
    }
  });

  // The normal from central differences of the cells' points, one-sided at holes; a cell with
  // no neighbour is taken as seen head-on.
  const auto at = [&](int i, int j, const Eigen::Vector3f& otherwise) -> const Eigen::Vector3f& {
    if (i < 0 || j < 0 || i >= grid_width_ || j >= grid_height_) return otherwise;
    const Eigen::Vector3f& p = cell_point_[static_cast<std::size_t>(j) * grid_width_ + i];
    return std::isnan(p.z()) ? otherwise : p;
  };
  runTasks(pool, tasks, [&](std::size_t task) {
    const int first = static_cast<int>(task) * kCellRowsPerTask;
    const int last = std::min(grid_height_, first + kCellRowsPerTask);
    for (int j = first; j < last; ++j) {
      float* out = cosine_.data() + static_cast<std::size_t>(j) * grid_width_;
      for (int i = 0; i < grid_width_; ++i) {
        const Eigen::Vector3f& p = cell_point_[static_cast<std::size_t>(j) * grid_width_ + i];
        out[i] = 1.0f;
        if (std::isnan(p.z())) continue;
        const Eigen::Vector3f across = at(i + 1, j, p) - at(i - 1, j, p);
        const Eigen::Vector3f down = at(i, j + 1, p) - at(i, j - 1, p);
        const Eigen::Vector3f normal = across.cross(down);
        const float n = normal.norm();
        if (n > 0.0f) out[i] = std::max(std::abs(normal.dot(p)) / (n * p.norm()), min_cos);
      }
    }
  });
}

namespace {

// A row of 8 voxels as vectors (GCC's vector extension: AVX in the x86-64-v3 clone of
// TsdfIntegrator::fuseBlock, pairs of SSE registers in the other).
constexpr int kRow = VoxelMap::kBlockEdge;
using RowFloats = float __attribute__((vector_size(4 * kRow)));
using RowInts = std::int32_t __attribute__((vector_size(4 * kRow)));
using RowWords = std::uint32_t __attribute__((vector_size(8 * kRow)));
// Unsigned where bits are packed and moved: shifts and sums on them must not overflow an int.
// (A C-style cast between vector types of one size keeps the bits.)
using RowUints = std::uint32_t __attribute__((vector_size(4 * kRow)));
static_assert(sizeof(VoxelMap::Voxel) == 8 && offsetof(VoxelMap::Voxel, weight_steps) == 2 &&
                  offsetof(VoxelMap::Voxel, r) == 4 && offsetof(VoxelMap::Voxel, observations) == 7,
              "a voxel is two 32-bit words as read below");
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "voxel words are read little-endian");
static_assert(kRow == 8, "a row of voxels is one vector of 8");

// What a view measured along a row of voxels: the signed distance to the surface, the band, the
// weight, which voxels it updates, which of those are near the surface, and the colour pixel
// each saw (-1: none).
struct RowMeasurement {
  RowFloats sdf, band, weight;
  RowInts update, near, colour_pixel;
};

// The row's voxels updated by `m` (Voxel::set and the colour blend, eight at a time). Inlined
// into both clones of fuseBlock: a vector function of its own would take the baseline's
// registers; and it takes its vectors by reference (by value, AVX vectors change the ABI).
[[gnu::always_inline]] inline void updateRow(const RowMeasurement& m, const std::uint8_t* color,
                                             VoxelMap::Voxel* row) {
  using Voxel = VoxelMap::Voxel;
  // The row's 8 voxels as 16 32-bit words: even ones hold the distance (low half) and the
  // weight, odd ones the colour (r lowest) and the observation count (highest byte).
  RowWords words;
  std::memcpy(&words, row, sizeof(words));
  const RowUints steps_word = __builtin_shufflevector(words, words, 0, 2, 4, 6, 8, 10, 12, 14);
  const RowUints colour_word = __builtin_shufflevector(words, words, 1, 3, 5, 7, 9, 11, 13, 15);
  const RowInts old_sdf_steps = (RowInts)(steps_word << 16) >> 16;  // sign-extended
  const RowInts old_weight_steps = (RowInts)(steps_word >> 16);
  const RowFloats old_sdf = __builtin_convertvector(old_sdf_steps, RowFloats) * Voxel::kSdfStep;
  const RowFloats old_weight =
      __builtin_convertvector(old_weight_steps, RowFloats) * Voxel::kWeightStep;
  const RowFloats alpha = m.update ? m.weight / (old_weight + m.weight) : 0.0f;
  const RowFloats target = m.sdf < m.band ? m.sdf : m.band;
  const RowFloats new_sdf = old_sdf + alpha * (target - old_sdf);
  const RowFloats summed = old_weight + m.weight;
  const RowFloats new_weight = summed < Voxel::kMaxWeight ? summed : Voxel::kMaxWeight;
  // Voxel::set(new_sdf, new_weight), eight at a time.
  RowFloats s = new_sdf * (1.0f / Voxel::kSdfStep);
  s = s < -32767.0f ? -32767.0f : s;
  s = s > 32767.0f ? 32767.0f : s;
  const RowInts sdf_steps =
      __builtin_convertvector(m.update ? s + 32768.5f : 32768.0f, RowInts) - 32768;
  RowFloats ws = new_weight * (1.0f / Voxel::kWeightStep) + 0.5f;
  ws = ws < 1.0f ? 1.0f : ws;
  ws = ws > 65535.0f ? 65535.0f : ws;
  const RowInts weight_steps = __builtin_convertvector(m.update ? ws : 0.0f, RowInts);
  const RowUints new_steps_word = ((RowUints)sdf_steps & 0xffffu) | ((RowUints)weight_steps << 16);

  // Near the surface: its colour, blended by the measurement's share of the weight. Only the
  // pixels are fetched one by one.
  const RowInts coloured = m.update & m.near & (m.colour_pixel >= 0);
  RowUints seen = colour_word;
  if (anyOf(coloured)) {
    for (int x = 0; x < kRow; ++x) {
      if (!coloured[x]) continue;
      const std::uint8_t* c = color + 3 * static_cast<std::ptrdiff_t>(m.colour_pixel[x]);
      seen[x] = c[2] | (c[1] << 8u) | (c[0] << 16u);  // BGR in the image, r lowest here
    }
  }
  const RowUints share = __builtin_convertvector(alpha * 256.0f + 0.5f, RowUints);  // 0 to 256
  const RowUints keep = 256u - share;
  RowUints blended = colour_word & 0xff000000u;
  for (int channel = 0; channel < 24; channel += 8) {
    const RowUints before = (colour_word >> channel) & 0xffu, after = (seen >> channel) & 0xffu;
    blended |= ((before * keep + after * share + 128u) >> 8) << channel;
  }
  RowUints new_colour_word = coloured ? blended : colour_word;
  // Observations count up to 255.
  const RowUints observations = colour_word >> 24;
  new_colour_word += (m.update & (observations < 255u)) ? RowUints{} + (1u << 24) : RowUints{};

  const RowUints stored_steps = m.update ? new_steps_word : steps_word;
  words = __builtin_shufflevector(stored_steps, new_colour_word, 0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5,
                                  13, 6, 14, 7, 15);
  std::memcpy(static_cast<void*>(row), &words, sizeof(words));  // trivially copyable
}

}  // namespace

// Compiled for AVX2 too: the projection of a row of 8 voxels then takes one instruction per step.
RGBDMAP_VECTOR_CLONES void TsdfIntegrator::fuseBlock(const ImageView& view,
                                                     VoxelMap::Block& block) const {
  // A row of 8 voxels is updated as one vector; only the pixels are fetched one by one. It
  // cannot call scalar functions, so it repeats bandAt() and Voxel::set() (with the same named
  // constants: KinectNoise, Voxel's steps); what it calls is inlined (updateRow).
  const RowFloats steps = {0, 1, 2, 3, 4, 5, 6, 7};
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx) + 0.5f, cy = static_cast<float>(camera.cy) + 0.5f;
  const float fwidth = static_cast<float>(view.width), fheight = static_cast<float>(view.height);
  const float narrowest = static_cast<float>(truncation);
  const float sigmas = static_cast<float>(truncation_sigmas);
  const float sigma_at_1m = kinectDepthSigma(1.0f);
  const Eigen::Vector3f origin =
      view.world_to_camera *
      ((block.origin.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * view.voxel);
  for (int z = 0; z < kRow; ++z) {
    for (int y = 0; y < kRow; ++y) {
      const Eigen::Vector3f start =
          origin + static_cast<float>(y) * view.dy + static_cast<float>(z) * view.dz;
      const RowFloats px = start.x() + steps * view.dx.x();
      const RowFloats py = start.y() + steps * view.dx.y();
      const RowFloats pz = start.z() + steps * view.dx.z();
      const RowFloats inv_z = 1.0f / pz;
      const RowFloats uf = fx * px * inv_z + cx;  // + 0.5: truncation rounds to nearest
      const RowFloats vf = fy * py * inv_z + cy;
      // Behind the camera u and v are anything (NaN included): selected away before converting.
      const RowInts inside =
          (pz > 0.0f) & (uf >= 0.0f) & (vf >= 0.0f) & (uf < fwidth) & (vf < fheight);
      if (!anyOf(inside)) continue;
      const RowInts u = __builtin_convertvector(inside ? uf : 0.0f, RowInts);
      const RowInts v = __builtin_convertvector(inside ? vf : 0.0f, RowInts);
      const RowInts pixel = v * view.width + u;
      const RowInts cell = (v >> cell_bits_) * grid_width_ + (u >> cell_bits_);  // incidenceAt()
      RowFloats d, scale;
      for (int x = 0; x < kRow; ++x) {
        d[x] = view.depth[pixel[x]];
        scale[x] = cosine_[cell[x]];
      }
      RowMeasurement m;
      m.sdf = (d - pz) * scale;                            // to the surface, not the pixel
      const RowFloats band_from = d - KinectNoise::kFrom;  // kinectDepthSigma(d), the band from it
      const RowFloats sigma = KinectNoise::kBase + KinectNoise::kGrowth * band_from * band_from;
      const RowFloats wide = sigmas * sigma;
      m.band = wide > narrowest ? wide : narrowest;
      // Behind the surface by more than the band: nothing known.
      m.update = inside & (d > 0.0f) & (m.sdf >= -m.band);
      if (!anyOf(m.update)) continue;
      m.near = m.sdf < m.band;
      m.colour_pixel = pixel;  // -1: no colour pixel saw this one
      if (view.color_pixel_of)
        for (int x = 0; x < kRow; ++x) m.colour_pixel[x] = view.color_pixel_of[pixel[x]];
      // Free space: as sure as a measurement at the voxel's own depth would be (a far surface
      // seen through a voxel leaves no doubt that it is empty).
      const RowFloats weighed_at = (m.near ? d : pz) - KinectNoise::kFrom;
      const RowFloats weighed_sigma =
          KinectNoise::kBase + KinectNoise::kGrowth * weighed_at * weighed_at;
      const RowFloats ratio = sigma_at_1m / weighed_sigma;
      m.weight = m.update ? ratio * ratio * scale : 0.0f;
      updateRow(m, view.color, block.voxels.data() + (z * kRow + y) * kRow);
    }
  }
}

void TsdfIntegrator::integrate(const cv::Mat& depth_in, const cv::Mat& color_in,
                               const Eigen::Isometry3d& pose, VoxelMap& map, WorkerPool* pool,
                               const int* color_pixel_of) {
  CV_Assert(depth_in.type() == CV_32FC1 && color_in.type() == CV_8UC3 &&
            color_in.size() == depth_in.size());
  const cv::Mat& depth = contiguous(depth_in, depth_);
  const cv::Mat& color_bgr = contiguous(color_in, color_);
  prepareIncidence(depth, pool);
  map.beginIntegration();
  const Eigen::Isometry3f world_to_camera = pose.inverse().cast<float>();
  if (map.integrations() % std::max(1, seen_through_every) == 0)
    touchSeenThrough(depth, world_to_camera, map, pool);
  allocate(depth, pose, map, pool);

  ImageView view;
  view.world_to_camera = world_to_camera;
  view.voxel = static_cast<float>(map.voxelSize());
  const Eigen::Matrix3f Rcw = world_to_camera.linear();
  view.dx = Rcw.col(0) * view.voxel;
  view.dy = Rcw.col(1) * view.voxel;
  view.dz = Rcw.col(2) * view.voxel;
  view.depth = depth.ptr<float>();
  view.color = color_bgr.ptr<std::uint8_t>();
  view.color_pixel_of = color_pixel_of;
  view.width = depth.cols;
  view.height = depth.rows;
  const std::vector<std::uint32_t>& touched = map.touchedBlocks();
  auto fuse_blocks = [&](std::size_t task) {
    const std::size_t first = task * kBlocksPerTask;
    const std::size_t last = std::min(touched.size(), first + kBlocksPerTask);
    for (std::size_t b = first; b < last; ++b) fuseBlock(view, map.block(touched[b]));
  };
  const std::size_t tasks = (touched.size() + kBlocksPerTask - 1) / kBlocksPerTask;
  runTasks(pool, tasks, fuse_blocks);
  map.finishIntegration();
}

}  // namespace rgbdmap
