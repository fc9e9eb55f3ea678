#pragma once

#include <string>

#include "rgbdmap/base/option_keys.hpp"
#include "rgbdmap/config/config.hpp"

namespace rgbdmap {

// The topics of a `rosbag:` source (config section "ros", "" = detected; see chooseBagTopics).
// The node takes its topics by remapping instead. The core does not know this section: it is
// added to every Config by ros_options.cpp, an object linked into each program that links the
// ROS adapter.
struct RosOptions {
  std::string color_topic;
  std::string depth_topic;
  std::string camera_info_topic;
};

Keys rosKeys(RosOptions& o);

// The section in a run's configuration.
RosOptions& rosOptions(Config& config);
const RosOptions& rosOptions(const Config& config);

}  // namespace rgbdmap
