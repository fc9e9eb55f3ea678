#pragma once

#include <string>
#include <vector>

#include "rgbdmap/base/option_keys.hpp"
#include "rgbdmap/base/option_sections.hpp"
#include "rgbdmap/capture/camera_options.hpp"
#include "rgbdmap/config/run_options.hpp"
#include "rgbdmap/mapping/depth_filter.hpp"
#include "rgbdmap/mapping/free_space_map.hpp"
#include "rgbdmap/mapping/ground_frame.hpp"
#include "rgbdmap/mapping/keyframe_selector.hpp"
#include "rgbdmap/mapping/map_options.hpp"
#include "rgbdmap/mapping/occupancy_grid.hpp"
#include "rgbdmap/slam/loop_options.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"
#include "rgbdmap/tracking/tracking_options.hpp"

namespace rgbdmap {

// Every tunable of a run: the option structs of the layers, one member per config section
// ("section.name" keys set field `name` of member `section`), which YAML files, `--set` and ROS
// parameters fill. Each layer keeps its struct, its defaults and its key table; this joins them.
// Adapters outside the core (ros/) add their sections through `sections`.
struct Config {
  std::string preset;  // name of the preset the camera section came from, for the log

  CameraOptions camera;      // camera.*      (capture)
  ReplayOptions replay;      // replay.*      (runtime)
  QueueOptions queue;        // queue.*       (runtime)
  PoseOptions pose;          // pose.*        (tracking)
  TrackingOptions tracking;  // tracking.*    (tracking): odometry without ground truth
  LoopOptions loop;          // loop.*        (slam): loop closure for the dense tracker
  RefusionOptions refusion;  // loop.refusion_*, loop.keyframe_* (mapping): the map follows loops
  KeyframeOptions keyframe;  // keyframe.*    (mapping)
  FilterOptions filter;      // filter.*      (mapping)
  MapOptions map;            // map.*         (mapping)
  CheckpointOptions checkpoint;  // checkpoint.*  (runtime)
  UpOptions up;                  // up.*          (mapping): which way is up, where the floor is
  GridOptions grid;              // grid.*        (mapping): the occupancy grid (--grid)
  OctomapOptions octomap;        // octomap.*     (mapping): the OctoMap (--octomap)
  OptionSections sections;       // e.g. ros.*    (registered by adapters)

  // Every key, bound to this instance, in the order of docs/configuration.md.
  Keys keys();

  // Sets one key from text; throws InputError naming the key (and `origin`) when the key is
  // unknown or the value is invalid or out of range.
  void set(const std::string& key, const std::string& value, const std::string& origin);
  // Sets each "key=value" of `assignments` (the command line's --set, named by `origin`).
  void setAll(const std::vector<std::string>& assignments, const std::string& origin);
  // Applies a YAML file (nested maps, e.g. `map: {voxel_size: 0.01}`); throws InputError.
  void loadYaml(const std::string& path);
  // Loads a preset by name from the config folder ("tum_fr1") or a path to a YAML file.
  void loadPreset(const std::string& name_or_path);
  std::string toYaml();
  static std::string presetDirectory() { return rgbdmap::presetDirectory(); }
};

}  // namespace rgbdmap
