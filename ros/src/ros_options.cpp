#include "rgbdmap/ros/ros_options.hpp"

namespace rgbdmap {
namespace {

// The ros.* keys follow the pose.* ones in the key table (and docs/configuration.md).
[[maybe_unused]] const bool registered = OptionSections::add<RosOptions>("pose", &rosKeys);

}  // namespace

Keys rosKeys(RosOptions& o) {
  return {
      // ROS sources (rosbag:, rgbdmap_node); the core only keeps the names.
      text("ros.color_topic", &o.color_topic,
           "rosbag: colour image topic (empty: TUM's /camera/rgb/image_color or the one colour "
           "image topic)"),
      text("ros.depth_topic", &o.depth_topic,
           "rosbag: depth image topic, 32FC1 metres or 16UC1 millimetres (empty: detected)"),
      text("ros.camera_info_topic", &o.camera_info_topic,
           "rosbag: camera_info topic (empty: camera_info beside the colour topic)"),
  };
}

RosOptions& rosOptions(Config& config) { return config.sections.get<RosOptions>(); }
const RosOptions& rosOptions(const Config& config) { return config.sections.get<RosOptions>(); }

}  // namespace rgbdmap
