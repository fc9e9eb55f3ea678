#pragma once

#include <ros/ros.h>

#include <string>

#include "rgbdmap/config/config.hpp"

namespace rgbdmap {

// The node's own settings, private parameters beside the config keys.
struct NodeSettings {
  std::string config;        // ~config: preset name or YAML file ("default")
  std::string out;           // ~out: the map (PCD)
  std::string stats;         // ~stats: counters as JSON at exit ("" = none)
  std::string map_frame;     // ~map_frame
  std::string camera_frame;  // ~camera_frame ("" = the colour images' frame_id)
  double map_interval = 2;   // ~map_interval: seconds between published maps at least
  // ~map_max_points: /rgbdmap/map thinned to at most this many points (0: whole)
  std::size_t map_max_points = 2'000'000;
  double grid_interval = 5;  // ~grid_interval: seconds between published grids (< 0: no ~grid)
  // ~session_interval: seconds between looks at the graph for ~session/graph and
  // ~session/places (<= 0: not streamed); ~session_rate: bytes a second they stay under.
  double session_interval = 0.5;
  double session_rate = 500e3;
  std::string grid;     // ~grid: the grid's PGM (and YAML) written with every save ("" = none)
  std::string octomap;  // ~octomap: the OctoMap written with every save and ~save_octomap
  bool octomap_given = false;  // ~octomap set (else OUT.bt beside ~out, when mapping)
  // ~localise: a saved session (MAP.session) to localise in instead of mapping: poses and TF in
  // its map's frame, nothing mapped ("" = map).
  std::string localise;
  // ~continue: a saved session (MAP.session) to go on mapping from: the node maps in its own frame
  // until it recognises a saved place, then in the saved map's, and ~out gets one map and one
  // session of both ("" = map from nothing). No OctoMap (a session keeps no free space).
  std::string continue_from;
  // ~lossless: for a bag played into the node: every image is kept until mapped (nothing dropped
  // when mapping falls behind), the run is a replay's (its map does not depend on the machine's
  // speed), and ~intake tells the player how far the node has got, so that rgbdmap-play waits
  // for it. A camera does not wait: leave it off for one.
  bool lossless = false;
};

NodeSettings readNodeSettings(const ros::NodeHandle& private_nh);

// Every config key as a private parameter, '.' written '/': _map/voxel_size:=0.005 sets
// map.voxel_size. Throws InputError naming the parameter when a value is wrong.
void applyPrivateParams(const ros::NodeHandle& private_nh, Config& config);

}  // namespace rgbdmap
