#include "rgbdmap/sim/synthetic_sequence.hpp"

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <tsl/hopscotch_map.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/core/utility.hpp>
#include <random>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/image_file.hpp"
#include "rgbdmap/base/tum_pose_line.hpp"
#include "rgbdmap/base/voxel_key_hash.hpp"

namespace rgbdmap {
namespace {

// A seed for one image row of one frame, so noise does not depend on how rows are scheduled.
std::uint64_t rowSeed(std::uint64_t seed, int frame, int row) {
  std::uint64_t x = seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(frame) * 1000003ull +
                    static_cast<std::uint64_t>(row);
  x ^= x >> 31;
  x *= 0xBF58476D1CE4E5B9ull;
  x ^= x >> 29;
  return x;
}

std::string stampName(double stamp) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.6f", stamp);
  return text;
}

void validate(const SyntheticSequenceOptions& o) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw InputError("synthetic sequence: " + what);
  };
  require(o.frames > 0 || (o.frames == 0 && o.path == "tour"),
          "frames must be positive (0, one whole tour, only for the tour)");
  require(o.fps > 0.0 && o.fps <= 1000.0, "fps must be in (0, 1000]");
  require(o.loop_seconds > 0.0, "loop_seconds must be positive");
  require(o.path_radius >= 0.0, "path_radius must not be negative");
  require(o.path == "orbit" || o.path == "walk" || o.path == "line" || o.path == "tour",
          "path '" + o.path + "' is unknown (expected orbit, walk, line or tour)");
  require(o.tour_speed > 0.0 && o.tour_speed <= 3.0, "tour_speed must be in (0, 3] m/s");
  require(o.tour_turn_rate > 0.0 && o.tour_turn_rate <= 3.0,
          "tour_turn_rate must be in (0, 3] rad/s");
  require(o.tour_margin >= 0.0, "tour_margin must not be negative");
  require(o.path_inset >= 0.0, "path_inset must not be negative");
  require(std::abs(o.depth_scale_error) < 0.2, "depth_scale_error must be within +-0.2");
  require(std::abs(o.focal_error) < 0.2, "focal_error must be within +-0.2");
  require(o.depth_focal == 0 || (o.depth_focal >= 100 && o.depth_focal <= 3000),
          "depth_focal must be 0 (the declared focal length) or 100-3000 px");
  require(o.brightness_drift >= 0.0 && o.brightness_drift < 0.9,
          "brightness_drift must be in [0, 0.9)");
  require(o.depth_offset >= 0.0 && o.depth_offset_jitter >= 0.0 &&
              o.depth_offset + o.depth_offset_jitter < 0.019,
          "depth offset + jitter must stay below TUM's 0.02 s association window");
  require(o.depth_offset + o.depth_offset_jitter < 0.5 / o.fps,
          "depth offset + jitter must be under half a frame interval");
  require(o.readout >= 0.0 && o.readout <= 1.0 / o.fps,
          "readout must be in [0, one frame interval]");
  require(o.groundtruth_rate >= o.fps, "groundtruth_rate must be at least fps");
  require(o.camera.width > 0 && o.camera.height > 0 && o.camera.fx > 0 && o.camera.fy > 0,
          "camera intrinsics must be positive");
  require(!o.camera.hasDistortion(), "the renderer models no lens distortion");
  require(o.depth_scale > 0.0 && o.max_range * o.depth_scale <= 65535.0,
          "max_range * depth_scale must fit a 16-bit depth image");
  require(o.min_range >= 0.0 && o.min_range < o.max_range, "min_range must be below max_range");
  require(o.dropout >= 0.0 && o.dropout < 1.0, "dropout must be in [0, 1)");
  require(o.max_incidence_deg > 0.0 && o.max_incidence_deg <= 90.0,
          "max_incidence_deg must be in (0, 90]");
  require(o.surface_voxel > 0.0, "surface_voxel must be positive");
  require(o.png_compression >= 0 && o.png_compression <= 9, "png_compression must be 0..9");
}

// visible_surface.pcd: the first exact hit that falls into each voxel (a point on the surface,
// where a voxel centroid would sit off the surface at edges and on curves).
class SurfaceSampler {
 public:
  explicit SurfaceSampler(double voxel) : inverse_voxel_(1.0 / voxel) {}

  void add(const cv::Vec3f& p, const cv::Vec3b& bgr) {
    const std::uint64_t key = keyOf(p);
    if (index_.find(key) != index_.end()) return;
    index_.emplace(key, static_cast<std::uint32_t>(cloud_.size()));
    pcl::PointXYZRGB point;
    point.x = p[0];
    point.y = p[1];
    point.z = p[2];
    point.b = bgr[0];
    point.g = bgr[1];
    point.r = bgr[2];
    cloud_.push_back(point);
  }
  pcl::PointCloud<pcl::PointXYZRGB>& cloud() { return cloud_; }

 private:
  std::uint64_t keyOf(const cv::Vec3f& p) const {
    // 21 bits per axis around the origin: +-5 km at 5 mm, far beyond any room.
    auto cell = [&](float v) {
      return static_cast<std::uint64_t>(std::floor(v * inverse_voxel_) + (1 << 20)) & 0x1FFFFF;
    };
    return cell(p[0]) | cell(p[1]) << 21 | cell(p[2]) << 42;
  }

  double inverse_voxel_;
  tsl::hopscotch_map<std::uint64_t, std::uint32_t, VoxelKeyHash> index_;
  pcl::PointCloud<pcl::PointXYZRGB> cloud_;
};

void writeImage(const std::string& path, const cv::Mat& image, int compression) {
  std::string error;
  if (!writeImageFile(path, image, error, compression)) throw InputError(error);
}

void writeOptions(const std::string& path, const SyntheticSequenceOptions& o,
                  const SyntheticSequenceSummary& summary) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "generator" << YAML::Value << "rgbdmap synth";
  out << YAML::Key << "frames" << YAML::Value << o.frames;
  out << YAML::Key << "fps" << YAML::Value << o.fps;
  out << YAML::Key << "seed" << YAML::Value << o.seed;
  out << YAML::Key << "noise_seed" << YAML::Value << o.noise_seed;
  out << YAML::Key << "path_radius" << YAML::Value << o.path_radius;
  out << YAML::Key << "noise" << YAML::Value << o.noise;
  out << YAML::Key << "loop_seconds" << YAML::Value << o.loop_seconds;
  out << YAML::Key << "path" << YAML::Value << o.path;
  out << YAML::Key << "path_inset" << YAML::Value << o.path_inset;
  if (o.depthUnregistered()) {
    // The truth `rgbdmap calibrate` and the camera.depth_* keys are checked against.
    const Eigen::Vector3d& t = o.depth_camera_position;
    const Eigen::Vector3d& r = o.depth_camera_rotation;
    out << YAML::Key << "depth_camera" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "position_m" << YAML::Value << YAML::Flow << YAML::BeginSeq << t.x()
        << t.y() << t.z() << YAML::EndSeq;
    out << YAML::Key << "rotation_vector_rad" << YAML::Value << YAML::Flow << YAML::BeginSeq
        << r.x() << r.y() << r.z() << YAML::EndSeq;
    out << YAML::Key << "focal_px" << YAML::Value
        << (o.depth_focal > 0 ? o.depth_focal : o.camera.fx);
    out << YAML::EndMap;
  }
  if (o.path == "tour") {
    out << YAML::Key << "tour_speed" << YAML::Value << o.tour_speed;
    out << YAML::Key << "tour_turn_rate" << YAML::Value << o.tour_turn_rate;
    out << YAML::Key << "tour_length_m" << YAML::Value << summary.path_length;
    out << YAML::Key << "tour_seconds" << YAML::Value << summary.path_seconds;
  }
  out << YAML::Key << "depth_scale_error" << YAML::Value << o.depth_scale_error;
  out << YAML::Key << "focal_error" << YAML::Value << o.focal_error;
  out << YAML::Key << "brightness_drift" << YAML::Value << o.brightness_drift;
  if (o.readout > 0) out << YAML::Key << "readout" << YAML::Value << o.readout;
  out << YAML::Key << "camera" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "width" << YAML::Value << o.camera.width;
  out << YAML::Key << "height" << YAML::Value << o.camera.height;
  out << YAML::Key << "fx" << YAML::Value << o.camera.fx;
  out << YAML::Key << "fy" << YAML::Value << o.camera.fy;
  out << YAML::Key << "cx" << YAML::Value << o.camera.cx;
  out << YAML::Key << "cy" << YAML::Value << o.camera.cy;
  out << YAML::EndMap;
  out << YAML::Key << "depth_scale" << YAML::Value << o.depth_scale;
  out << YAML::Key << "range" << YAML::Value << YAML::Flow << YAML::BeginSeq << o.min_range
      << o.max_range << YAML::EndSeq;
  out << YAML::Key << "dropout" << YAML::Value << o.dropout;
  out << YAML::Key << "max_incidence_deg" << YAML::Value << o.max_incidence_deg;
  out << YAML::Key << "surface_voxel" << YAML::Value << o.surface_voxel;
  out << YAML::Key << "surface_points" << YAML::Value << summary.surface_points;
  out << YAML::EndMap;
  std::ofstream file(path);
  file << out.c_str() << '\n';
  file.flush();
  if (!file) throw InputError(path + ": cannot write");
}

}  // namespace

double kinectDepthSigma(double z) { return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4); }

std::unique_ptr<CameraPath> makeCameraPath(const ScenePrimitive& room,
                                           const SyntheticSequenceOptions& options,
                                           double duration) {
  const Eigen::Vector3d size = room.max - room.min;
  const double inset = options.path_inset > 0.0
                           ? options.path_inset
                           : std::clamp(0.2 * std::min(size.x(), size.y()), 0.8, 1.5);
  // A walk needs room for its rectangle, a line for its length.
  const double free_x = size.x() - 2.0 * inset, free_y = size.y() - 2.0 * inset;
  if (options.path != "orbit" && (free_x < 0.5 || (options.path == "walk" && free_y < 0.5))) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "synthetic sequence: a path inset of %.2f m leaves no room for the %s path in a "
                  "%.1f x %.1f m room",
                  inset, options.path.c_str(), size.x(), size.y());
    throw InputError(text);
  }
  if (options.path == "tour")
    throw InputError(
        "synthetic sequence: the tour needs a building's floor plan (rgbdmap synth --building, or "
        "a scene.yaml with a floor_plan)");
  if (options.path == "walk")
    return std::make_unique<WalkPath>(room, options.seed, options.loop_seconds, inset);
  if (options.path == "line")
    return std::make_unique<LinePath>(room, options.seed, duration, inset);
  return std::make_unique<HandheldPath>(room, options.seed, options.loop_seconds,
                                        options.path_radius);
}

std::unique_ptr<CameraPath> makeCameraPath(const SyntheticScene& scene,
                                           const SyntheticSequenceOptions& options,
                                           double duration) {
  if (options.path != "tour") return makeCameraPath(scene.room(), options, duration);
  const FloorPlan* plan = scene.floorPlan();
  if (!plan)
    throw InputError(
        "synthetic sequence: the tour needs a floor plan, and this scene has none (rgbdmap synth "
        "--building makes one; a scene.yaml may have a floor_plan: see docs/synthetic.md)");
  return std::make_unique<TourPath>(*plan, options.seed, options.tour_speed,
                                    options.tour_turn_rate);
}

SyntheticRenderer::SyntheticRenderer(const SyntheticScene& scene, const CameraIntrinsics& camera)
    : scene_(scene), camera_(camera) {
  rays_.resize(static_cast<std::size_t>(camera.width) * camera.height);
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u)
      rays_[static_cast<std::size_t>(v) * camera.width + u] =
          Eigen::Vector3d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
  const ScenePrimitive& room = scene.room();
  light_ = 0.5 * (room.min + room.max);
  light_.z() = room.max.z() - 0.3;
}

void SyntheticRenderer::render(const Eigen::Isometry3d& pose, cv::Mat& depth, cv::Mat& color,
                               cv::Mat& incidence_cos, cv::Mat& hits) const {
  render(std::vector<Eigen::Isometry3d>(static_cast<std::size_t>(camera_.height), pose), depth,
         color, incidence_cos, hits);
}

void SyntheticRenderer::render(const std::vector<Eigen::Isometry3d>& row_poses, cv::Mat& depth,
                               cv::Mat& color, cv::Mat& incidence_cos, cv::Mat& hits) const {
  const int width = camera_.width, height = camera_.height;
  depth.create(height, width, CV_32FC1);
  color.create(height, width, CV_8UC3);
  incidence_cos.create(height, width, CV_32FC1);
  hits.create(height, width, CV_32FC3);
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const Eigen::Isometry3d& pose = row_poses[static_cast<std::size_t>(v)];
      const Eigen::Matrix3d rotation = pose.linear();
      const Eigen::Vector3d origin = pose.translation();
      auto* depth_row = depth.ptr<float>(v);
      auto* color_row = color.ptr<cv::Vec3b>(v);
      auto* cos_row = incidence_cos.ptr<float>(v);
      auto* hit_row = hits.ptr<cv::Vec3f>(v);
      for (int u = 0; u < width; ++u) {
        const Eigen::Vector3d& ray = rays_[static_cast<std::size_t>(v) * width + u];
        const Eigen::Vector3d direction = rotation * ray;
        double t = 0.0;
        Eigen::Vector3d normal;
        cv::Vec3b albedo;
        if (!scene_.raycast(origin, direction, t, normal, albedo)) {
          depth_row[u] = 0.0f;
          color_row[u] = cv::Vec3b(0, 0, 0);
          cos_row[u] = 0.0f;
          hit_row[u] = cv::Vec3f(0, 0, 0);
          continue;
        }
        // The ray has z = 1 in the camera frame, so t is the depth along the optical axis.
        depth_row[u] = static_cast<float>(t);
        const Eigen::Vector3d point = origin + t * direction;
        hit_row[u] = cv::Vec3f(static_cast<float>(point.x()), static_cast<float>(point.y()),
                               static_cast<float>(point.z()));
        cos_row[u] = static_cast<float>(-normal.dot(direction) / direction.norm());
        // Lambertian light from a fixed lamp: shading depends on the surface only, not on the
        // view, so the brightness-constancy assumption of RGB odometry holds.
        const double lit = std::max(0.0, normal.dot((light_ - point).normalized()));
        const double shade = 0.6 + 0.4 * lit;
        for (int c = 0; c < 3; ++c)
          color_row[u][c] = static_cast<unsigned char>(std::lround(albedo[c] * shade));
      }
    }
  });
}

namespace {

// groundtruth.txt: the analytic path sampled at options.groundtruth_rate, a little beyond the
// frames at both ends; refused where the path comes too close to a surface.
void writeGroundTruth(const std::string& folder, const SyntheticScene& scene,
                      const CameraPath& path, double duration,
                      const SyntheticSequenceOptions& options) {
  const int gt_margin = 5;  // samples of ground truth before the first and after the last frame
  const int gt_samples = static_cast<int>(std::ceil(duration * options.groundtruth_rate));
  const bool tour = options.path == "tour";
  const double margin =
      tour ? std::max(options.camera_margin, options.tour_margin) : options.camera_margin;
  for (int k = -gt_margin; k <= gt_samples + gt_margin; ++k) {
    const Eigen::Vector3d p = path.pose(k / options.groundtruth_rate).translation();
    if (!scene.isFreeSpace(p, margin))
      throw InputError("synthetic sequence: the " + options.path + " path comes within " +
                       std::to_string(margin) +
                       " m of a surface at t = " + std::to_string(k / options.groundtruth_rate) +
                       " s; the scene leaves too little free space " +
                       (options.path == "orbit" ? "around the room's centre"
                        : tour                  ? "along the floor plan's corridor, doors and stops"
                                                : "inside the walls (try another --path-inset)"));
  }

  std::ofstream groundtruth(folder + "/groundtruth.txt");
  groundtruth << "# ground truth trajectory (rgbdmap synth, analytic path sampled at "
              << options.groundtruth_rate << " Hz)\n"
              << kTumPoseHeader;
  for (int k = -gt_margin; k <= gt_samples + gt_margin; ++k) {
    const double t = k / options.groundtruth_rate;
    groundtruth << tumPoseLine(options.start_time + t, path.pose(t), 9) << '\n';
  }
  groundtruth.flush();
  if (!groundtruth) throw InputError(folder + "/groundtruth.txt: cannot write");
}

// accelerometer.txt as TUM's Kinect logs it, at the ground truth's rate: the specific force (the
// path's acceleration, by central differences, minus gravity, 9.81 m/s^2 along the scene's -z)
// in the camera frame, its x and y negated (the Kinect's axes: AccelerometerLog::upInCamera).
void writeAccelerometer(const std::string& folder, const CameraPath& path, double duration,
                        const SyntheticSequenceOptions& options) {
  const double h = 1.0 / options.groundtruth_rate;
  const int samples = static_cast<int>(std::ceil(duration * options.groundtruth_rate));
  std::ofstream out(folder + "/accelerometer.txt");
  out << "# accelerometer data (rgbdmap synth: the analytic path's specific force)\n"
      << "# timestamp ax ay az\n";
  char line[128];
  for (int k = 0; k <= samples; ++k) {
    const double t = k * h;
    const Eigen::Isometry3d pose = path.pose(t);
    const Eigen::Vector3d acceleration =
        (path.pose(t + h).translation() - 2.0 * pose.translation() +
         path.pose(t - h).translation()) /
        (h * h);
    const Eigen::Vector3d force =
        pose.linear().transpose() * (acceleration + Eigen::Vector3d(0.0, 0.0, 9.81));
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f\n", options.start_time + t, -force.x(),
                  -force.y(), force.z());
    out << line;
  }
  out.flush();
  if (!out) throw InputError(folder + "/accelerometer.txt: cannot write");
}

// What the sensor measures of frame `frame`'s ideal depth `depth` (metres, from the renderer):
// 16-bit depth in `depth16` with the configured errors and noise, the colour noise applied to
// `color` in place, and in `visible` the pixels an ideal sensor measures (the reference surface).
void measure(const cv::Mat& depth, const cv::Mat& incidence_cos, int frame,
             const SyntheticSequenceOptions& options, cv::Mat& color, cv::Mat& depth16,
             cv::Mat& visible) {
  const CameraIntrinsics& camera = options.camera;
  const int i = frame;
  const float min_cos = static_cast<float>(std::cos(options.max_incidence_deg * M_PI / 180.0));
  cv::parallel_for_(cv::Range(0, camera.height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      std::mt19937_64 random(rowSeed(options.noise_seed, i, v));
      std::normal_distribution<float> gauss(0.0f, 1.0f);
      std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
      const auto* z_row = depth.ptr<float>(v);
      const auto* cos_row = incidence_cos.ptr<float>(v);
      auto* out_row = depth16.ptr<std::uint16_t>(v);
      auto* visible_row = visible.ptr<unsigned char>(v);
      auto* color_row = color.ptr<cv::Vec3b>(v);
      for (int u = 0; u < camera.width; ++u) {
        const double z = z_row[u];
        // The reference surface is what an ideal sensor measures: in range, not grazing.
        const bool measurable =
            z >= options.min_range && z <= options.max_range && cos_row[u] >= min_cos;
        visible_row[u] = measurable ? 1 : 0;
        double measured = measurable ? z * (1.0 + options.depth_scale_error) : 0.0;
        if (options.noise) {
          // Draw every random number for every pixel so the stream does not depend on hits.
          const double n = gauss(random);
          const bool dropped = uniform(random) < options.dropout;
          for (int c = 0; c < 3; ++c) {
            const double value = color_row[u][c] + options.color_noise * gauss(random);
            color_row[u][c] = static_cast<unsigned char>(std::clamp(std::lround(value), 0l, 255l));
          }
          if (measured > 0.0) measured += kinectDepthSigma(z) * n;
          if (dropped || measured < options.min_range || measured > options.max_range)
            measured = 0.0;
        }
        out_row[u] = static_cast<std::uint16_t>(std::lround(measured * options.depth_scale));
      }
    }
  });
}

// A frame's colour and depth images, encoded side by side (PNG encoding is most of a frame's
// cost). An exception must not leave a worker thread, so each job reports its error as text.
void writeImages(const std::string& rgb_path, const cv::Mat& color, const std::string& depth_path,
                 const cv::Mat& depth16, int compression) {
  std::string write_errors[2];
  cv::parallel_for_(cv::Range(0, 2), [&](const cv::Range& jobs) {
    for (int job = jobs.start; job < jobs.end; ++job) {
      try {
        if (job == 0)
          writeImage(rgb_path, color, compression);
        else
          writeImage(depth_path, depth16, compression);
      } catch (const std::exception& e) {
        write_errors[job] = e.what();
      }
    }
  });
  for (const std::string& error : write_errors)
    if (!error.empty()) throw InputError(error);
}

// visible_surface.pcd: the surface the frames saw, sampled (what `rgbdmap evaluate` scores
// against).
const pcl::PointCloud<pcl::PointXYZRGB>& writeSurface(const std::string& folder,
                                                      SurfaceSampler& surface) {
  const std::string surface_path = folder + "/visible_surface.pcd";
  pcl::PointCloud<pcl::PointXYZRGB>& cloud = surface.cloud();
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
  if (cloud.empty() || pcl::io::savePCDFileBinary(surface_path, cloud) != 0)
    throw InputError(surface_path + ": cannot write the visible surface" +
                     (cloud.empty() ? std::string(" (the camera saw no surface in range)") : ""));
  return cloud;
}

}  // namespace

SyntheticSequenceSummary writeSyntheticSequence(const std::string& folder,
                                                const SyntheticScene& scene,
                                                const SyntheticSequenceOptions& options) {
  namespace fs = std::filesystem;
  validate(options);
  const auto start = std::chrono::steady_clock::now();
  std::error_code ec;
  for (const char* sub : {"rgb", "depth"}) {
    fs::create_directories(fs::path(folder) / sub, ec);
    if (ec) throw InputError(folder + "/" + sub + ": cannot create folder (" + ec.message() + ")");
  }

  const std::unique_ptr<CameraPath> camera_path =
      makeCameraPath(scene, options, (std::max(options.frames, 1) - 1) / options.fps);
  const CameraPath& path = *camera_path;
  const auto* tour = dynamic_cast<const TourPath*>(&path);
  // frames = 0: one whole tour, ending where it began.
  const int frames = options.frames > 0 || !tour
                         ? options.frames
                         : static_cast<int>(std::floor(tour->duration() * options.fps)) + 1;
  const double duration = (frames - 1) / options.fps;
  writeGroundTruth(folder, scene, path, duration, options);
  writeAccelerometer(folder, path, duration, options);

  std::ofstream rgb_list(folder + "/rgb.txt"), depth_list(folder + "/depth.txt");
  rgb_list << "# color images (rgbdmap synth)\n# timestamp filename\n";
  depth_list << "# depth images (rgbdmap synth), 16-bit PNG, " << options.depth_scale
             << " units per metre, 0 = no measurement\n# timestamp filename\n";

  const CameraIntrinsics& camera = options.camera;
  // The lens the images are rendered through; the sequence declares `camera`.
  CameraIntrinsics lens = camera;
  lens.fx *= 1.0 + options.focal_error;
  lens.fy *= 1.0 + options.focal_error;
  const SyntheticRenderer renderer(scene, lens);
  // A depth camera of its own has exact intrinsics (those the camera.depth_* keys declare).
  CameraIntrinsics depth_lens = camera;
  if (options.depth_focal > 0) depth_lens.fx = depth_lens.fy = options.depth_focal;
  const SyntheticRenderer depth_renderer(scene, depth_lens);
  SurfaceSampler surface(options.surface_voxel);
  cv::Mat depth, color, incidence_cos, hits;
  cv::Mat depth16(camera.height, camera.width, CV_16UC1);
  cv::Mat visible(camera.height, camera.width, CV_8UC1);
  std::size_t valid_pixels = 0;
  const bool unregistered = options.depthUnregistered();
  Eigen::Isometry3d color_from_depth = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d& rotation = options.depth_camera_rotation;
  if (!rotation.isZero())
    color_from_depth.linear() = Eigen::AngleAxisd(rotation.norm(), rotation.normalized()).matrix();
  color_from_depth.translation() = options.depth_camera_position;
  cv::Mat color_depth, color_incidence, color_hits, depth_color;
  std::vector<Eigen::Isometry3d> row_poses(static_cast<std::size_t>(camera.height));
  std::mt19937_64 stamp_random(options.seed ^ 0x5EEDull);
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  for (int i = 0; i < frames; ++i) {
    const double t = i / options.fps;
    const double rgb_stamp = options.start_time + t;
    const double depth_stamp =
        rgb_stamp + options.depth_offset + options.depth_offset_jitter * unit(stamp_random);
    // Row v read (v / height - 1/2) readouts after the stamp.
    for (int v = 0; v < camera.height; ++v)
      row_poses[static_cast<std::size_t>(v)] =
          path.pose(t + (static_cast<double>(v) / camera.height - 0.5) * options.readout);
    if (unregistered) {
      // Colour from the colour camera; depth, and the surface it measures, from the depth one.
      renderer.render(row_poses, color_depth, color, color_incidence, color_hits);
      for (Eigen::Isometry3d& pose : row_poses) pose = pose * color_from_depth;
      depth_renderer.render(row_poses, depth, depth_color, incidence_cos, hits);
    } else {
      renderer.render(row_poses, depth, color, incidence_cos, hits);
    }
    const double gain = 1.0 + options.brightness_drift * std::sin(2.0 * M_PI * t / 6.0);
    if (gain != 1.0) color.convertTo(color, -1, gain);

    measure(depth, incidence_cos, i, options, color, depth16, visible);
    valid_pixels += static_cast<std::size_t>(cv::countNonZero(depth16));
    for (int v = 0; v < camera.height; ++v) {
      const auto* visible_row = visible.ptr<unsigned char>(v);
      const auto* hit_row = hits.ptr<cv::Vec3f>(v);
      const auto* color_row = (unregistered ? depth_color : color).ptr<cv::Vec3b>(v);
      for (int u = 0; u < camera.width; ++u)
        if (visible_row[u]) surface.add(hit_row[u], color_row[u]);
    }

    const std::string rgb_name = "rgb/" + stampName(rgb_stamp) + ".png";
    const std::string depth_name = "depth/" + stampName(depth_stamp) + ".png";
    writeImages(folder + "/" + rgb_name, color, folder + "/" + depth_name, depth16,
                options.png_compression);
    rgb_list << stampName(rgb_stamp) << ' ' << rgb_name << '\n';
    depth_list << stampName(depth_stamp) << ' ' << depth_name << '\n';
  }
  rgb_list.flush();
  depth_list.flush();
  if (!rgb_list) throw InputError(folder + "/rgb.txt: cannot write");
  if (!depth_list) throw InputError(folder + "/depth.txt: cannot write");

  try {
    scene.save(folder + "/scene.yaml");
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }
  const pcl::PointCloud<pcl::PointXYZRGB>& cloud = writeSurface(folder, surface);

  SyntheticSequenceSummary summary;
  summary.frames = frames;
  if (tour) {
    summary.path_length = tour->length();
    summary.path_seconds = tour->duration();
  }
  summary.surface_points = cloud.size();
  summary.valid_depth_share = static_cast<double>(valid_pixels) /
                              (static_cast<double>(frames) * camera.width * camera.height);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  SyntheticSequenceOptions written = options;
  written.frames = frames;
  writeOptions(folder + "/synthetic.yaml", written, summary);
  return summary;
}

}  // namespace rgbdmap
