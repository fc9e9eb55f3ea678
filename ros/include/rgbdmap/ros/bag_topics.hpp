#pragma once

#include <string>
#include <utility>
#include <vector>

#include "rgbdmap/ros/ros_options.hpp"

namespace rgbdmap {

// The RGB-D topics of a bag: the ros.* keys when set; otherwise TUM's names, then the names
// openni2_camera and freenect_camera record, then the one image topic that looks like colour
// (or depth). Throws InputError naming the bag and listing its image topics when none or more
// than one fits.
struct BagTopics {
  std::string color;
  std::string depth;
  std::string camera_info;  // "" when the bag has none: the preset's intrinsics are used
};

// `topics`: every topic of the bag with its message type.
BagTopics chooseBagTopics(const std::string& bag,
                          const std::vector<std::pair<std::string, std::string>>& topics,
                          const RosOptions& keys);

}  // namespace rgbdmap
