// original_method: the mapping method rgbdmap grew from, reimplemented with PCL as the baseline
// the benchmarks compare against. Kept faithful on purpose, including its costs and its flaws:
//  - it reads the 12-column association (colour, depth, ground truth) of a TUM sequence;
//  - it preloads every frame into memory before mapping (its memory behaviour);
//  - every N-th frame is a keyframe, back-projected with the pinhole intrinsics (no
//    undistortion) and its ground-truth pose into a pcl::PointCloud<pcl::PointXYZRGB>;
//  - pcl::StatisticalOutlierRemoval (mean-k 50, stddev 1.0) on each keyframe cloud;
//  - keyframe clouds gather in a window; every few keyframes the window is concatenated,
//    voxel-filtered with pcl::VoxelGrid and appended to the map;
//  - one final pcl::VoxelGrid over the map at the leaf size, written as binary PCD.
// pcl::VoxelGrid returns its input unfiltered when the cloud's extent / leaf overflows 32-bit
// indices. The original has that bug and so does this program; it counts and reports each hit.
#include <pcl/common/common.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/runtime/source_factory.hpp"

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZRGB>;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// One line of TUM's associate_with_groundtruth.txt:
// t_rgb rgb/x.png t_depth depth/y.png t_gt tx ty tz qx qy qz qw
struct AssociationRow {
  double rgb_time = 0.0;
  std::string rgb_path;
  double depth_time = 0.0;
  std::string depth_path;
  double groundtruth_time = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

std::string relativeTo(const std::string& folder, const std::string& path) {
  const std::string prefix = folder + "/";
  return path.rfind(prefix, 0) == 0 ? path.substr(prefix.size()) : path;
}

// The association the original read from disk, made with TUM's rule by rgbdmap::TumSequence.
// Frames without ground truth are not in it (associating with groundtruth.txt drops them).
std::vector<AssociationRow> associate(const std::string& folder, double depth_scale) {
  rgbdmap::TumSequence::Options options;
  options.depth_scale = depth_scale;
  const rgbdmap::TumSequence sequence(folder, options);
  std::vector<AssociationRow> rows;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const rgbdmap::TumEntry& e = sequence[i];
    if (!e.pose) continue;
    // Ground truth is interpolated at the colour stamp, so that is its time.
    rows.push_back({e.rgb_time, relativeTo(sequence.folder(), e.rgb_path), e.depth_time,
                    relativeTo(sequence.folder(), e.depth_path), e.rgb_time, *e.pose});
  }
  return rows;
}

void writeAssociation(const std::vector<AssociationRow>& rows, const std::string& path) {
  std::ofstream out(path);
  // Poses with every digit a double carries: reading the file back gives the same poses.
  constexpr int kExact = std::numeric_limits<double>::max_digits10;
  out << std::fixed;
  for (const AssociationRow& r : rows) {
    const Eigen::Quaterniond q(r.pose.linear());
    const Eigen::Vector3d t = r.pose.translation();
    out << std::setprecision(6) << r.rgb_time << ' ' << r.rgb_path << ' ' << r.depth_time << ' '
        << r.depth_path << ' ' << r.groundtruth_time << ' ' << std::setprecision(kExact) << t.x()
        << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
        << q.w() << '\n';
  }
  if (!out) throw rgbdmap::InputError(path + ": cannot write the association");
}

std::vector<AssociationRow> readAssociation(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw rgbdmap::InputError(path + ": cannot open the association");
  std::vector<AssociationRow> rows;
  std::string line;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    AssociationRow r;
    double tx, ty, tz, qx, qy, qz, qw;
    if (!(fields >> r.rgb_time >> r.rgb_path >> r.depth_time >> r.depth_path >>
          r.groundtruth_time >> tx >> ty >> tz >> qx >> qy >> qz >> qw))
      throw rgbdmap::InputError(path + ":" + std::to_string(number) +
                                ": expected 12 columns (t_rgb rgb t_depth depth t_gt tx ty tz "
                                "qx qy qz qw)");
    r.pose.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    r.pose.translation() = Eigen::Vector3d(tx, ty, tz);
    rows.push_back(std::move(r));
  }
  return rows;
}

// A frame as the original kept it: the decoded images, untouched.
struct PreloadedFrame {
  cv::Mat color;  // CV_8UC3, BGR
  cv::Mat depth;  // CV_16UC1, depth units
};

PreloadedFrame preload(const std::string& folder, const AssociationRow& row) {
  PreloadedFrame f;
  const std::string color_path = folder + "/" + row.rgb_path;
  const std::string depth_path = folder + "/" + row.depth_path;
  f.color = cv::imread(color_path, cv::IMREAD_COLOR);
  f.depth = cv::imread(depth_path, cv::IMREAD_UNCHANGED);
  if (f.color.empty()) throw rgbdmap::InputError(color_path + ": cannot read image");
  if (f.depth.empty() || f.depth.type() != CV_16UC1)
    throw rgbdmap::InputError(depth_path + ": cannot read a 16-bit depth image");
  if (f.depth.size() != f.color.size())
    throw rgbdmap::InputError(depth_path + ": size differs from " + color_path);
  return f;
}

// Pinhole back-projection of every pixel with a depth, straight into world coordinates.
void backProject(const PreloadedFrame& frame, const rgbdmap::CameraIntrinsics& camera,
                 double depth_scale, const Eigen::Isometry3d& pose, Cloud& cloud) {
  const Eigen::Affine3f camera_to_world = pose.cast<float>();
  cloud.clear();
  for (int v = 0; v < frame.depth.rows; ++v) {
    const auto* depth_row = frame.depth.ptr<std::uint16_t>(v);
    const auto* color_row = frame.color.ptr<cv::Vec3b>(v);
    for (int u = 0; u < frame.depth.cols; ++u) {
      if (depth_row[u] == 0) continue;
      const double z = depth_row[u] / depth_scale;
      const Eigen::Vector3f p_camera(static_cast<float>((u - camera.cx) * z / camera.fx),
                                     static_cast<float>((v - camera.cy) * z / camera.fy),
                                     static_cast<float>(z));
      pcl::PointXYZRGB p;
      p.getVector3fMap() = camera_to_world * p_camera;
      p.b = color_row[u][0];
      p.g = color_row[u][1];
      p.r = color_row[u][2];
      cloud.push_back(p);
    }
  }
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
}

// pcl::VoxelGrid, plus a count of the times it silently returned its input because the
// voxel indices of the cloud's extent would overflow 32 bits (same test as PCL 1.13's).
struct VoxelGridFilter {
  float leaf = 0.01f;
  int overflows = 0;

  void apply(const Cloud::ConstPtr& input, Cloud& output) {
    Eigen::Vector4f min_p, max_p;
    pcl::getMinMax3D(*input, min_p, max_p);
    const float inverse_leaf = 1.0f / leaf;
    const auto cells = [&](int axis) {
      return static_cast<std::int64_t>((max_p[axis] - min_p[axis]) * inverse_leaf) + 1;
    };
    if (!input->empty() && cells(0) * cells(1) * cells(2) >
                               static_cast<std::int64_t>(std::numeric_limits<std::int32_t>::max()))
      ++overflows;
    pcl::VoxelGrid<pcl::PointXYZRGB> grid;
    grid.setInputCloud(input);
    grid.setLeafSize(leaf, leaf, leaf);
    grid.filter(output);
  }
};

// Nearest-rank percentile (the rule rgbdmap's latency histograms use), of sorted values.
double percentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::min(std::max<std::size_t>(rank, 1), sorted.size()) - 1];
}

struct Options {
  std::string sequence;
  std::string association;        // read this 12-column file instead of associating
  std::string write_association;  // save the association made from the sequence
  std::string config;             // preset name or YAML; default: as rgbdmap picks it
  std::string out = "original_map.pcd";
  std::string json;
  int every_n = 10;
  double leaf = 0.01;
  int sor_mean_k = 50;
  double sor_stddev = 1.0;
  int window_keyframes = 5;
  bool quiet = false;
};

int run(const Options& o) {
  const auto start = Clock::now();
  rgbdmap::Config config;
  config.loadPreset(o.config.empty() ? rgbdmap::presetForSource("tum:" + o.sequence) : o.config);
  const rgbdmap::CameraIntrinsics& camera = config.camera;

  std::vector<AssociationRow> rows = o.association.empty()
                                         ? associate(o.sequence, config.camera.depth_scale)
                                         : readAssociation(o.association);
  if (!o.write_association.empty()) writeAssociation(rows, o.write_association);
  if (rows.empty()) throw rgbdmap::InputError(o.sequence + ": no frame has ground truth");

  const auto preload_start = Clock::now();
  std::vector<PreloadedFrame> frames;
  frames.reserve(rows.size());
  for (const AssociationRow& row : rows) frames.push_back(preload(o.sequence, row));
  const double preload_seconds = secondsSince(preload_start);

  const auto mapping_start = Clock::now();
  VoxelGridFilter voxel_grid{static_cast<float>(o.leaf)};
  Cloud::Ptr keyframe_cloud(new Cloud), filtered(new Cloud), window(new Cloud),
      compressed(new Cloud), map(new Cloud);
  int keyframes_in_window = 0;
  const auto flushWindow = [&] {
    voxel_grid.apply(window, *compressed);
    *map += *compressed;
    window->clear();
    keyframes_in_window = 0;
  };
  std::vector<double> keyframe_ms;
  std::vector<std::size_t> keyframe_points;
  for (std::size_t i = 0; i < frames.size(); i += static_cast<std::size_t>(o.every_n)) {
    const auto keyframe_start = Clock::now();
    backProject(frames[i], camera, config.camera.depth_scale, rows[i].pose, *keyframe_cloud);
    pcl::StatisticalOutlierRemoval<pcl::PointXYZRGB> sor;
    sor.setInputCloud(keyframe_cloud);
    sor.setMeanK(o.sor_mean_k);
    sor.setStddevMulThresh(o.sor_stddev);
    sor.filter(*filtered);
    *window += *filtered;
    if (++keyframes_in_window == o.window_keyframes) flushWindow();
    keyframe_ms.push_back(secondsSince(keyframe_start) * 1e3);
    keyframe_points.push_back(filtered->size());
    if (!o.quiet)
      std::fprintf(stderr, "keyframe %zu (frame %zu): %zu points, %zu after SOR, %.1f ms\n",
                   keyframe_ms.size(), i, keyframe_cloud->size(), filtered->size(),
                   keyframe_ms.back());
  }
  const auto final_start = Clock::now();
  if (keyframes_in_window > 0) flushWindow();
  Cloud result;
  voxel_grid.apply(map, result);
  const double final_ms = secondsSince(final_start) * 1e3;
  const double mapping_seconds = secondsSince(mapping_start);
  const double wall_seconds = secondsSince(start);

  if (pcl::io::savePCDFileBinary(o.out, result) != 0)
    throw rgbdmap::InputError(o.out + ": cannot write the map");
  if (voxel_grid.overflows > 0)
    std::fprintf(stderr,
                 "note: pcl::VoxelGrid returned its input unfiltered %d time(s): the extent / "
                 "leaf overflows 32-bit indices (the original method's bug, kept)\n",
                 voxel_grid.overflows);

  std::vector<double> sorted = keyframe_ms;
  std::sort(sorted.begin(), sorted.end());
  const double peak_rss_mb = rgbdmap::peakRssMb();
  std::ostringstream json;
  json.precision(6);
  json << "{\n"
       << "  \"system\": \"original_method\",\n"
       << "  \"frames\": " << frames.size() << ",\n"
       << "  \"keyframes\": " << keyframe_ms.size() << ",\n"
       << "  \"every_n\": " << o.every_n << ",\n"
       << "  \"wall_seconds\": " << wall_seconds << ",\n"
       << "  \"preload_seconds\": " << preload_seconds << ",\n"
       << "  \"mapping_seconds\": " << mapping_seconds << ",\n"
       << "  \"frames_per_second\": " << static_cast<double>(frames.size()) / wall_seconds << ",\n"
       << "  \"keyframe_ms\": {\"count\": " << sorted.size()
       << ", \"p50_ms\": " << percentile(sorted, 0.5) << ", \"p90_ms\": " << percentile(sorted, 0.9)
       << ", \"p95_ms\": " << percentile(sorted, 0.95)
       << ", \"max_ms\": " << percentile(sorted, 1.0) << "},\n"
       << "  \"final_voxel_grid_ms\": " << final_ms << ",\n"
       << "  \"voxel_grid_overflows\": " << voxel_grid.overflows << ",\n"
       << "  \"peak_rss_mb\": " << peak_rss_mb << ",\n"
       << "  \"map_points\": " << result.size() << ",\n"
       << "  \"per_keyframe\": [";
  for (std::size_t k = 0; k < keyframe_ms.size(); ++k)
    json << (k ? ", " : "") << "{\"frame\": " << k * static_cast<std::size_t>(o.every_n)
         << ", \"ms\": " << keyframe_ms[k] << ", \"points\": " << keyframe_points[k] << "}";
  json << "]\n}\n";
  if (!o.json.empty()) {
    std::ofstream out(o.json);
    out << json.str();
    if (!out) throw rgbdmap::InputError(o.json + ": cannot write statistics");
  }
  if (!o.quiet) std::fputs(json.str().c_str(), stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{
      "The original PCL mapping method (preload, every N-th frame, SOR, VoxelGrid "
      "window), as the benchmarks' baseline"};
  app.add_option("sequence", o.sequence,
                 "TUM sequence folder (rgb.txt, depth.txt, groundtruth.txt)")
      ->required();
  app.add_option("--association", o.association,
                 "12-column association file (paths relative to the sequence folder) to read "
                 "instead of associating the folder's lists");
  app.add_option("--write-association", o.write_association,
                 "write the association made from the folder's lists here");
  app.add_option("-c,--config", o.config,
                 "camera preset name or YAML (default: the one rgbdmap picks for the folder)");
  app.add_option("-o,--out", o.out, "map to write (binary PCD)")->capture_default_str();
  app.add_option("--json", o.json, "write timing and totals as JSON");
  app.add_option("--every", o.every_n, "every N-th frame is a keyframe")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--leaf", o.leaf, "VoxelGrid leaf size (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--sor-mean-k", o.sor_mean_k, "StatisticalOutlierRemoval mean k")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--sor-stddev", o.sor_stddev, "StatisticalOutlierRemoval stddev multiplier")
      ->capture_default_str();
  app.add_option("--window", o.window_keyframes,
                 "keyframes gathered before the window is voxel-filtered into the map")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_flag("-q,--quiet", o.quiet, "no per-keyframe lines and no JSON on stdout");
  CLI11_PARSE(app, argc, argv);
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "original_method: %s\n", e.what());
    return 1;
  }
}
