#include "rgbdmap/ros/bag_topics.hpp"

#include <algorithm>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {
namespace {

using TopicList = std::vector<std::pair<std::string, std::string>>;

const char* const kImage = "sensor_msgs/Image";
const char* const kCameraInfo = "sensor_msgs/CameraInfo";

// Well-known names, most specific first: TUM, then openni2_camera / freenect_camera.
const std::vector<std::string> kColorNames = {"/camera/rgb/image_color", "/camera/rgb/image_raw",
                                              "/camera/rgb/image_rect_color"};
const std::vector<std::string> kDepthNames = {
    "/camera/depth/image", "/camera/depth_registered/image_raw", "/camera/depth_registered/image",
    "/camera/depth/image_raw"};

std::string typeOf(const TopicList& topics, const std::string& name) {
  for (const auto& [topic, type] : topics)
    if (topic == name) return type;
  return "";
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

std::string imageTopicList(const TopicList& topics) {
  std::string list;
  for (const auto& [topic, type] : topics)
    if (type == kImage) list += (list.empty() ? "" : ", ") + topic;
  return list.empty() ? "none" : list;
}

std::string pick(const std::string& bag, const TopicList& topics, const std::string& key_value,
                 const char* key, const std::vector<std::string>& known, bool depth) {
  const std::string what = depth ? "depth" : "colour";
  if (!key_value.empty()) {
    const std::string type = typeOf(topics, key_value);
    if (type.empty())
      throw InputError(bag + ": " + key + "=" + key_value + ": no such topic in the bag (image " +
                       "topics: " + imageTopicList(topics) + ")");
    if (type != kImage)
      throw InputError(bag + ": " + key_value + " holds " + type + ", not " + kImage);
    return key_value;
  }
  for (const std::string& name : known)
    if (typeOf(topics, name) == kImage) return name;
  std::vector<std::string> candidates;
  for (const auto& [topic, type] : topics) {
    if (type != kImage) continue;
    const bool looks_depth = contains(topic, "depth");
    const bool looks_color = contains(topic, "rgb") || contains(topic, "color") ||
                             contains(topic, "colour") || contains(topic, "image_raw");
    if (depth ? looks_depth : (looks_color && !looks_depth)) candidates.push_back(topic);
  }
  if (candidates.size() == 1) return candidates.front();
  if (candidates.empty())
    throw InputError(bag + ": no " + what + " image topic (sensor_msgs/Image topics: " +
                     imageTopicList(topics) + "); name one with --set " + key + "=TOPIC");
  std::string list;
  for (const std::string& c : candidates) list += (list.empty() ? "" : ", ") + c;
  throw InputError(bag + ": " + std::to_string(candidates.size()) + " topics could be the " + what +
                   " images (" + list + "); choose one with --set " + key + "=TOPIC");
}

}  // namespace

BagTopics chooseBagTopics(const std::string& bag, const TopicList& topics, const RosOptions& keys) {
  BagTopics chosen;
  chosen.color = pick(bag, topics, keys.color_topic, "ros.color_topic", kColorNames, false);
  chosen.depth = pick(bag, topics, keys.depth_topic, "ros.depth_topic", kDepthNames, true);
  if (!keys.camera_info_topic.empty()) {
    if (typeOf(topics, keys.camera_info_topic) != kCameraInfo)
      throw InputError(bag + ": ros.camera_info_topic=" + keys.camera_info_topic +
                       ": no sensor_msgs/CameraInfo topic of that name in the bag");
    chosen.camera_info = keys.camera_info_topic;
  } else {
    // The colour camera's info: the mapper works in the colour camera's frame (depth registered).
    const std::string sibling =
        chosen.color.substr(0, chosen.color.find_last_of('/') + 1) + "camera_info";
    if (typeOf(topics, sibling) == kCameraInfo) chosen.camera_info = sibling;
  }
  return chosen;
}

}  // namespace rgbdmap
