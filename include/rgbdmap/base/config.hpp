#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/loop_options.hpp"
#include "rgbdmap/base/tracking_options.hpp"

namespace rgbdmap {

// Every tunable of a run. Each field is a config key ("section.name") that YAML files and
// `--set key=value` can change; see Config::keys() for ranges and meanings.
struct Config {
  std::string preset;  // name of the preset the camera section came from, for the log

  CameraIntrinsics camera;
  double depth_scale = 5000.0;  // camera.depth_scale: depth units per metre (TUM 5000)
  // camera.intrinsics: "preset" (the camera.fx/fy/cx/cy above) or "device" (from the field of
  // view an OpenNI2 device reports; other sources ignore it).
  std::string camera_intrinsics = "preset";

  double rate = 1.0;       // replay.rate: 1 = recorded speed, 0 = as fast as possible (lossless)
  int queue_capacity = 8;  // queue.capacity

  std::string pose_source = "auto";  // pose.source: auto | groundtruth | odometry | trajectory
  std::string pose_trajectory;       // pose.trajectory: TUM file for pose.source=trajectory
  double pose_max_gap = 0.05;        // pose.max_gap: s to the nearest ground truth sample

  // ros.*: topics of a rosbag: source ("" = detected); the node takes its topics by remapping.
  struct RosTopics {
    std::string color_topic;
    std::string depth_topic;
    std::string camera_info_topic;
  } ros;

  TrackingOptions tracking;  // tracking.*: odometry for sources without ground truth
  LoopOptions loop;          // loop.*: loop closure for the dense tracker

  std::string keyframe_policy = "auto";    // keyframe.policy: auto | interval | motion | both
  int keyframe_every_n = 10;               // keyframe.every_n
  double keyframe_min_translation = 0.05;  // keyframe.min_translation (m)
  double keyframe_min_rotation = 0.0873;   // keyframe.min_rotation (rad, 5 degrees)

  double min_depth = 0.3;  // filter.min_depth (m)
  double max_depth = 4.0;  // filter.max_depth (m)
  bool undistort = true;   // filter.undistort: undo lens distortion when the camera has it
  std::string outlier_filter = "fast";  // filter.outliers: fast | statistical | none
  double edge_jump = 0.03;       // filter.edge_jump: relative depth jump that marks a flying pixel
  int speck_min_neighbours = 4;  // filter.speck_min_neighbours: of 8, with similar depth
  bool subsample = true;         // filter.subsample: every 2nd pixel where 2 pixels < half a voxel
  int smooth_radius = 2;         // filter.smooth_radius: inverse-depth averaging window, 0 = off
  int sor_mean_k = 50;           // filter.sor_mean_k
  double sor_stddev = 1.0;       // filter.sor_stddev

  double voxel_size = 0.01;      // map.voxel_size (m)
  int map_min_observations = 1;  // map.min_observations: voxels seen fewer times are not written
  double map_truncation = 0.03;  // map.truncation: narrowest TSDF band (m)
  double map_truncation_sigmas = 3.0;     // map.truncation_sigmas: band in depth-noise sigmas
  double map_min_incidence_cosine = 0.2;  // map.min_incidence_cosine: clamp of cos(incidence)
  int map_fusion_threads =
      0;  // map.fusion_threads: 0 = every core in a replay, 1 for a live camera

  int checkpoint_every_keyframes = 50;   // checkpoint.every_keyframes (0 = off)
  double checkpoint_every_seconds = 60;  // checkpoint.every_seconds (0 = off)
  double checkpoint_min_seconds = 10;    // checkpoint.min_seconds

  // A key's name, help text and accessors bound to one Config instance.
  struct Key {
    std::string name;
    std::string help;
    std::function<void(const std::string&)> set;  // throws std::invalid_argument with why
    std::function<std::string()> get;
  };
  std::vector<Key> keys();

  // Sets one key from text; throws InputError naming the key (and `origin`) when the key is
  // unknown or the value is invalid or out of range.
  void set(const std::string& key, const std::string& value, const std::string& origin);
  // Applies a YAML file (nested maps, e.g. `map: {voxel_size: 0.01}`); throws InputError.
  void loadYaml(const std::string& path);
  // Loads a preset by name from the config folder ("tum_fr1") or a path to a YAML file.
  void loadPreset(const std::string& name_or_path);
  std::string toYaml();
  static std::string presetDirectory();
};

}  // namespace rgbdmap
