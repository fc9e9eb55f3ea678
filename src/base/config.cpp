#include "rgbdmap/base/config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {
namespace {

std::string formatNumber(double v) {
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

Config::Key number(const std::string& name, double* field, double lo, double hi,
                   const std::string& help) {
  return {name, help,
          [=](const std::string& text) {
            std::size_t used = 0;
            double v = 0;
            try {
              v = std::stod(text, &used);
            } catch (const std::exception&) {
              used = 0;
            }
            if (used == 0 || used != text.size() || !std::isfinite(v))
              throw std::invalid_argument("'" + text + "' is not a number");
            if (v < lo || v > hi)
              throw std::invalid_argument(text + " is outside [" + formatNumber(lo) + ", " +
                                          formatNumber(hi) + "]");
            *field = v;
          },
          [=] { return formatNumber(*field); }};
}

Config::Key integer(const std::string& name, int* field, int lo, int hi, const std::string& help) {
  return {name, help,
          [=](const std::string& text) {
            std::size_t used = 0;
            long v = 0;
            try {
              v = std::stol(text, &used);
            } catch (const std::exception&) {
              used = 0;
            }
            if (used == 0 || used != text.size())
              throw std::invalid_argument("'" + text + "' is not an integer");
            if (v < lo || v > hi)
              throw std::invalid_argument(text + " is outside [" + std::to_string(lo) + ", " +
                                          std::to_string(hi) + "]");
            *field = static_cast<int>(v);
          },
          [=] { return std::to_string(*field); }};
}

Config::Key boolean(const std::string& name, bool* field, const std::string& help) {
  return {name, help,
          [=](const std::string& text) {
            if (text == "true" || text == "1" || text == "yes" || text == "on")
              *field = true;
            else if (text == "false" || text == "0" || text == "no" || text == "off")
              *field = false;
            else
              throw std::invalid_argument("'" + text + "' is not true or false");
          },
          [=] { return std::string(*field ? "true" : "false"); }};
}

Config::Key choice(const std::string& name, std::string* field, std::vector<std::string> options,
                   const std::string& help) {
  return {name, help,
          [=](const std::string& text) {
            for (const std::string& o : options)
              if (o == text) {
                *field = text;
                return;
              }
            std::string list;
            for (const std::string& o : options) list += (list.empty() ? "" : ", ") + o;
            throw std::invalid_argument("'" + text + "' is not one of " + list);
          },
          [=] { return *field; }};
}

Config::Key text(const std::string& name, std::string* field, const std::string& help) {
  return {name, help, [=](const std::string& value) { *field = value; }, [=] { return *field; }};
}

// Flattens nested YAML maps into "a.b" keys with scalar values.
void flatten(const YAML::Node& node, const std::string& prefix,
             std::vector<std::pair<std::string, YAML::Node>>& out) {
  if (node.IsMap()) {
    for (const auto& item : node)
      flatten(item.second,
              prefix.empty() ? item.first.as<std::string>()
                             : prefix + "." + item.first.as<std::string>(),
              out);
  } else {
    out.emplace_back(prefix, node);
  }
}

}  // namespace

std::vector<Config::Key> Config::keys() {
  constexpr double kBig = 1e6;
  return {
      integer("camera.width", &camera.width, 16, 8192, "image width in pixels"),
      integer("camera.height", &camera.height, 16, 8192, "image height in pixels"),
      number("camera.fx", &camera.fx, 1, kBig, "focal length x (px)"),
      number("camera.fy", &camera.fy, 1, kBig, "focal length y (px)"),
      number("camera.cx", &camera.cx, -kBig, kBig, "principal point x (px)"),
      number("camera.cy", &camera.cy, -kBig, kBig, "principal point y (px)"),
      number("camera.k1", &camera.k1, -100, 100, "radial distortion k1"),
      number("camera.k2", &camera.k2, -100, 100, "radial distortion k2"),
      number("camera.p1", &camera.p1, -100, 100, "tangential distortion p1"),
      number("camera.p2", &camera.p2, -100, 100, "tangential distortion p2"),
      number("camera.k3", &camera.k3, -100, 100, "radial distortion k3"),
      number("camera.depth_scale", &depth_scale, 1e-3, kBig,
             "depth units per metre (TUM PNG 5000, OpenNI2 1000)"),
      // OpenNI2 sources: where the intrinsics come from.
      choice("camera.intrinsics", &camera_intrinsics, {"preset", "device"},
             "preset: camera.fx/fy/cx/cy; device: from the OpenNI2 device's field of view or "
             "the ROS camera_info (used anyway with the default preset and camera keys)"),
      number(
          "replay.rate", &rate, 0, 1000,
          "replay speed: 1 = as recorded (late frames dropped), 0 = as fast as possible, lossless"),
      integer("queue.capacity", &queue_capacity, 1, 1024,
              "frames queued between capture and mapping"),
      choice("pose.source", &pose_source, {"auto", "groundtruth", "odometry", "trajectory"},
             "where camera poses come from (auto: ground truth when the source has it, else "
             "odometry)"),
      text("pose.trajectory", &pose_trajectory, "TUM trajectory file when pose.source=trajectory"),
      number("pose.max_gap", &pose_max_gap, 0, 10,
             "a frame farther than this (s) from any pose sample gets no pose and is not mapped"),
      // ROS sources (rosbag:, rgbdmap_node); the core only keeps the names.
      text("ros.color_topic", &ros.color_topic,
           "rosbag: colour image topic (empty: TUM's /camera/rgb/image_color or the one colour "
           "image topic)"),
      text("ros.depth_topic", &ros.depth_topic,
           "rosbag: depth image topic, 32FC1 metres or 16UC1 millimetres (empty: detected)"),
      text("ros.camera_info_topic", &ros.camera_info_topic,
           "rosbag: camera_info topic (empty: camera_info beside the colour topic)"),
      choice("tracking.method", &tracking.method, {"dense", "opencv_rgbd", "opencv_rgbd_icp"},
             "odometry: dense (ours, against keyframes), opencv_rgbd or opencv_rgbd_icp (OpenCV)"),
      integer("tracking.coarsest_level", &tracking.coarsest_level, 1, 6,
              "dense: coarsest pyramid level aligned (each level halves the image)"),
      integer("tracking.finest_level", &tracking.finest_level, 0, 6,
              "dense: finest pyramid level aligned (0 = full resolution, 1 = 320x240)"),
      boolean("tracking.undistort", &tracking.undistort,
              "dense: undo lens distortion in the tracking pyramid (depth and 3-D points agree)"),
      integer("tracking.max_iterations", &tracking.max_iterations, 1, 100,
              "dense: Gauss-Newton steps per coarse level"),
      integer("tracking.finest_iterations", &tracking.finest_iterations, 1, 100,
              "dense: Gauss-Newton steps on the finest level"),
      number("tracking.depth_weight", &tracking.depth_weight, 0, 100,
             "dense: weight of depth residuals against intensity residuals (0 = photometric only)"),
      number("tracking.huber_k", &tracking.huber_k, 0.1, 100,
             "dense: Huber threshold in robust standard deviations"),
      number("tracking.min_gradient", &tracking.min_gradient, 0, 255,
             "dense: finest-level pixels with a weaker gradient (grey/px) are thinned to 1 in 4"),
      number("tracking.keyframe_translation", &tracking.keyframe_translation, 0, 10,
             "dense: a new tracking keyframe after moving this far (m)"),
      number("tracking.keyframe_rotation", &tracking.keyframe_rotation, 0, 3.15,
             "dense: a new tracking keyframe after turning this far (rad)"),
      number("tracking.keyframe_min_overlap", &tracking.keyframe_min_overlap, 0, 1,
             "dense: a new tracking keyframe when less of the last one is in view"),
      number("tracking.min_overlap", &tracking.min_overlap, 0, 1,
             "a frame is lost when less of the keyframe's pixels land in it"),
      number("tracking.min_depth_fraction", &tracking.min_depth_fraction, 0, 1,
             "a frame is lost (not mapped) when fewer of its pixels have depth"),
      number("tracking.max_residual", &tracking.max_residual, 0.1, 255,
             "a frame is lost when the intensity residual's robust std-dev exceeds this (grey)"),
      number("tracking.max_jump_translation", &tracking.max_jump_translation, 0.001, 10,
             "a frame is lost when it lands this far (m per frame period) from the prediction"),
      number("tracking.max_jump_rotation", &tracking.max_jump_rotation, 0.001, 3.15,
             "a frame is lost when it turns this far (rad per frame period) from the prediction"),
      integer("tracking.relocalisation_keyframes", &tracking.relocalisation_keyframes, 1, 1000,
              "recent keyframes kept to relocalise against after a loss"),
      integer("tracking.relocalisation_min_inliers", &tracking.relocalisation_min_inliers, 6, 10000,
              "ORB + PnP RANSAC inliers a relocalisation needs"),
      boolean("loop.enabled", &loop.enabled,
              "close loops (dense tracking only): place recognition, pose graph, map follows; "
              "false: odometry only"),
      integer("loop.recent_keyframes", &loop.recent_keyframes, 1, 100000,
              "the most recent tracking keyframes are not loop candidates"),
      number("loop.place_spacing", &loop.place_spacing, 0, 100,
             "a keyframe is kept for later loops unless a kept one is this near (m) and turned "
             "less than loop.place_spacing_angle"),
      number("loop.place_spacing_angle", &loop.place_spacing_angle, 0, 3.15,
             "see loop.place_spacing (rad; 0: keep every keyframe as a place)"),
      number("loop.search_radius", &loop.search_radius, 0, 100,
             "loop candidates lie this close to the keyframe's estimate (m), plus drift allowance"),
      number("loop.max_view_angle", &loop.max_view_angle, 0, 3.15,
             "loop candidates look within this angle of the keyframe's direction (rad)"),
      number("loop.drift_per_metre", &loop.drift_per_metre, 0, 10,
             "allowance for odometry drift per metre walked between candidate and keyframe"),
      integer("loop.max_candidates", &loop.max_candidates, 1, 100,
              "best-matching candidates verified geometrically per keyframe"),
      integer("loop.min_matches", &loop.min_matches, 6, 10000,
              "ORB ratio-test matches a candidate needs"),
      integer("loop.min_inliers", &loop.min_inliers, 6, 10000, "PnP RANSAC inliers a loop needs"),
      number("loop.min_overlap", &loop.min_overlap, 0, 1,
             "share of the candidate's pixels the dense verification must see"),
      integer("loop.finest_level", &loop.finest_level, 0, 6,
              "finest pyramid level of the dense loop check (0: full resolution)"),
      number("loop.depth_weight", &loop.depth_weight, 0, 100,
             "weight of the depth residual in the dense loop check"),
      number("loop.max_distance", &loop.max_distance, 0, 100,
             "a loop joins two keyframes at most this far apart, as measured (m)"),
      number("loop.max_disagreement_translation", &loop.max_disagreement_translation, 0, 10,
             "PnP and dense verification must agree within this (m)"),
      number("loop.max_disagreement_rotation", &loop.max_disagreement_rotation, 0, 3.15,
             "PnP and dense verification must agree within this (rad)"),
      integer("loop.consistency_keyframes", &loop.consistency_keyframes, 1, 1000,
              "a loop needs a consistent one from a keyframe at most this many keyframes away"),
      number("loop.consistent_translation", &loop.consistent_translation, 0, 10,
             "two loops are consistent when they correct a keyframe to within this (m)"),
      number("loop.consistent_rotation", &loop.consistent_rotation, 0, 3.15,
             "two loops are consistent when they correct a keyframe to within this (rad)"),
      number("loop.max_loop_residual", &loop.max_loop_residual, 0, 1e6,
             "a loop whose whitened residual stays above this after optimising is removed"),
      number("loop.edge_pixels", &loop.edge_pixels, 0.001, 1e9,
             "independent pixels an alignment is worth (scales every edge's information)"),
      integer("loop.submap_keyframes", &loop.submap_keyframes, 1, 1000000,
              "with loop closure: fused keyframes per submap of the map"),
      number("loop.submap_distance", &loop.submap_distance, 0.01, 1000,
             "with loop closure: a new submap after the camera moved this far from its start (m)"),
      number("loop.submap_rotation", &loop.submap_rotation, 0.01, 3.15,
             "with loop closure: a new submap after the camera turned this far (rad)"),
      choice("keyframe.policy", &keyframe_policy, {"auto", "interval", "motion", "both"},
             "interval: every N frames; motion: after moving; both: whichever comes first; auto: "
             "motion with odometry, else interval"),
      integer("keyframe.every_n", &keyframe_every_n, 1, 1000000, "frames between keyframes"),
      number("keyframe.min_translation", &keyframe_min_translation, 0, 100,
             "metres moved since the last keyframe that make a new one"),
      number("keyframe.min_rotation", &keyframe_min_rotation, 0, 3.15,
             "radians turned since the last keyframe that make a new one"),
      number("filter.min_depth", &min_depth, 0, 100, "nearest depth used (m)"),
      number("filter.max_depth", &max_depth, 0.01, 100, "farthest depth used (m)"),
      boolean("filter.undistort", &undistort, "undo lens distortion when the camera has it"),
      choice("filter.outliers", &outlier_filter, {"fast", "statistical", "none"},
             "fast: flying pixels and specks on the depth image; statistical: PCL's SOR"),
      number("filter.edge_jump", &edge_jump, 0.001, 1,
             "relative depth jump to a neighbour that marks a flying pixel"),
      integer("filter.speck_min_neighbours", &speck_min_neighbours, 0, 8,
              "neighbours (of 8) with similar depth a pixel needs to be kept"),
      boolean("filter.subsample", &subsample,
              "fuse every 2nd pixel of each row and column where 2 pixels span under half a voxel"),
      integer("filter.smooth_radius", &smooth_radius, 0, 10,
              "half-size of the edge-aware inverse-depth averaging window (0 = off)"),
      integer("filter.sor_mean_k", &sor_mean_k, 1, 1000, "statistical outlier removal: neighbours"),
      number("filter.sor_stddev", &sor_stddev, 0, 100, "statistical outlier removal: sigma"),
      number("map.voxel_size", &voxel_size, 0.001, 10, "voxel edge (m)"),
      integer("map.min_observations", &map_min_observations, 1, 255,
              "voxels seen in fewer frames are left out of written maps"),
      number("map.truncation", &map_truncation, 0.001, 10,
             "narrowest band around a measured surface that fusion updates (m)"),
      number("map.truncation_sigmas", &map_truncation_sigmas, 0, 100,
             "band around a measured surface in units of its depth noise sigma(z), if wider"),
      number("map.min_incidence_cosine", &map_min_incidence_cosine, 0.01, 1,
             "distances along a grazing line of sight are scaled by cos(incidence), clamped at "
             "this (1 = distances along the ray)"),
      integer("map.fusion_threads", &map_fusion_threads, 0, 256,
              "threads that update voxels (0 = every core when replaying, 1 with a live camera)"),
      integer("checkpoint.every_keyframes", &checkpoint_every_keyframes, 0, 100000000,
              "write a checkpoint every this many keyframes (0 = off)"),
      number("checkpoint.every_seconds", &checkpoint_every_seconds, 0, 1e9,
             "write a checkpoint every this many seconds (0 = off)"),
      number("checkpoint.min_seconds", &checkpoint_min_seconds, 0, 1e9,
             "checkpoints by keyframe count wait this long after the previous one (each writes "
             "the whole map: every frame a keyframe, 50 keyframes would rewrite it every 2 s)"),
  };
}

void Config::set(const std::string& key, const std::string& value, const std::string& origin) {
  for (Key& k : keys()) {
    if (k.name != key) continue;
    try {
      k.set(value);
    } catch (const std::invalid_argument& e) {
      throw InputError(origin + ": " + key + ": " + e.what());
    }
    if (min_depth >= max_depth)
      throw InputError(origin + ": " + key + ": filter.min_depth must be below filter.max_depth");
    return;
  }
  throw InputError(origin + ": unknown config key '" + key + "' (see `rgbdmap --list-keys`)");
}

void Config::loadYaml(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path + ": cannot open config file");
  } catch (const YAML::Exception& e) {
    throw InputError(path + ":" + std::to_string(e.mark.line + 1) + ": invalid YAML: " + e.msg);
  }
  if (root.IsNull()) return;
  if (!root.IsMap()) throw InputError(path + ": expected a map of config sections");
  std::vector<std::pair<std::string, YAML::Node>> items;
  flatten(root, "", items);
  for (const auto& [key, node] : items) {
    const std::string origin = path + ":" + std::to_string(node.Mark().line + 1);
    if (key == "preset") {
      preset = node.as<std::string>();
      continue;
    }
    if (!node.IsScalar()) throw InputError(origin + ": " + key + ": expected a single value");
    set(key, node.as<std::string>(), origin);
  }
}

std::string Config::presetDirectory() { return RGBDMAP_CONFIG_DIR; }

void Config::loadPreset(const std::string& name_or_path) {
  const bool is_path = name_or_path.find('/') != std::string::npos ||
                       name_or_path.find(".yaml") != std::string::npos;
  const std::string path =
      is_path ? name_or_path : presetDirectory() + "/" + name_or_path + ".yaml";
  if (!is_path && !std::ifstream(path))
    throw InputError("unknown preset '" + name_or_path + "' (no " + path + ")");
  preset = name_or_path;
  loadYaml(path);
}

std::string Config::toYaml() {
  std::ostringstream out;
  out << "# rgbdmap effective configuration";
  if (!preset.empty()) out << " (preset " << preset << ")";
  out << "\n";
  std::string section;
  for (const Key& k : keys()) {
    const std::string s = k.name.substr(0, k.name.find('.'));
    if (s != section) {
      section = s;
      out << section << ":\n";
    }
    std::string value = k.get();
    if (value.empty()) value = "\"\"";
    out << "  " << k.name.substr(k.name.find('.') + 1) << ": " << value << "  # " << k.help << "\n";
  }
  return out.str();
}

}  // namespace rgbdmap
