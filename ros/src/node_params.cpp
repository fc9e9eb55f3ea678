#include "rgbdmap/ros/node_params.hpp"

#include <cmath>
#include <cstdio>
#include <set>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/runtime/output_files.hpp"

namespace rgbdmap {
namespace {

// A parameter's value as the text a config file would hold.
std::string text(XmlRpc::XmlRpcValue& value, const std::string& name) {
  switch (value.getType()) {
    case XmlRpc::XmlRpcValue::TypeString:
      return static_cast<std::string>(value);
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return static_cast<bool>(value) ? "true" : "false";
    case XmlRpc::XmlRpcValue::TypeInt:
      return std::to_string(static_cast<int>(value));
    case XmlRpc::XmlRpcValue::TypeDouble: {
      char buffer[32];
      std::snprintf(buffer, sizeof buffer, "%.17g", static_cast<double>(value));
      return buffer;
    }
    default:
      throw InputError("parameter " + name + ": expected a single value");
  }
}

std::string stringParam(const ros::NodeHandle& nh, const std::string& name,
                        const std::string& fallback) {
  XmlRpc::XmlRpcValue value;
  if (!nh.getParam(name, value)) return fallback;
  return text(value, nh.resolveName(name));
}

double numberParam(const ros::NodeHandle& nh, const std::string& name,
                   const std::string& fallback) {
  const std::string value = stringParam(nh, name, fallback);
  try {
    std::size_t used = 0;
    const double number = std::stod(value, &used);
    if (used == value.size()) return number;
  } catch (const std::exception&) {
  }
  throw InputError("parameter " + nh.resolveName(name) + ": '" + value + "' is not a number");
}

bool boolParam(const ros::NodeHandle& nh, const std::string& name, bool fallback) {
  const std::string value = stringParam(nh, name, fallback ? "true" : "false");
  if (value == "true" || value == "1") return true;
  if (value == "false" || value == "0") return false;
  throw InputError("parameter " + nh.resolveName(name) + ": '" + value + "' is not true or false");
}

}  // namespace

NodeSettings readNodeSettings(const ros::NodeHandle& nh) {
  NodeSettings s;
  s.config = stringParam(nh, "config", "default");
  s.out = stringParam(nh, "out", "map.pcd");
  s.stats = stringParam(nh, "stats", "");
  s.map_frame = stringParam(nh, "map_frame", "map");
  s.camera_frame = stringParam(nh, "camera_frame", "");
  s.map_interval = numberParam(nh, "map_interval", "2");
  if (!(s.map_interval >= 0))
    throw InputError("parameter " + nh.resolveName("map_interval") + ": must be >= 0");
  const double max_points = numberParam(nh, "map_max_points", "2000000");
  if (!(max_points >= 0) || max_points != std::floor(max_points) || max_points > 4e9)
    throw InputError("parameter " + nh.resolveName("map_max_points") +
                     ": must be a whole number of points >= 0 (0: the whole map)");
  s.map_max_points = static_cast<std::size_t>(max_points);
  s.grid_interval = numberParam(nh, "grid_interval", "5");
  s.session_interval = numberParam(nh, "session_interval", "0.5");
  s.session_rate = numberParam(nh, "session_rate", "750000");
  if (!(s.session_rate > 0))
    throw InputError("parameter " + nh.resolveName("session_rate") + ": must be > 0 (bytes/s)");
  s.grid = stringParam(nh, "grid", "");
  s.octomap = stringParam(nh, "octomap", stem(s.out) + ".bt");
  s.octomap_given = nh.hasParam("octomap");
  s.localise = stringParam(nh, "localise", "");
  s.lossless = boolParam(nh, "lossless", false);
  s.continue_from = stringParam(nh, "continue", "");
  if (!s.continue_from.empty() && !s.localise.empty())
    throw InputError("parameter " + nh.resolveName("continue") + ": localising (" +
                     nh.resolveName("localise") + ") maps nothing to continue; give one");
  // Localising maps nothing and a continued session keeps no free space: no OctoMap beside ~out
  // (one asked for is refused, chooseRunMode).
  if (!s.localise.empty() || !s.continue_from.empty()) s.octomap.clear();
  return s;
}

void applyPrivateParams(const ros::NodeHandle& nh, Config& config) {
  // A misspelt parameter would otherwise be ignored in silence, as an unknown --set key is not.
  std::vector<std::string> names;
  const std::string prefix = nh.getNamespace() + "/";
  const std::set<std::string> settings = {
      "config",        "out",      "stats",         "map_frame", "camera_frame", "map_interval",
      "grid_interval", "grid",     "octomap",       "localise",  "continue",     "session_interval",
      "session_rate",  "lossless", "map_max_points"};
  std::set<std::string> keys;
  for (const Key& key : config.keys()) keys.insert(key.name);
  if (ros::param::getParamNames(names)) {
    for (const std::string& name : names) {
      if (name.rfind(prefix, 0) != 0) continue;
      std::string key = name.substr(prefix.size());
      if (settings.count(key)) continue;
      for (char& c : key)
        if (c == '/') c = '.';
      if (!keys.count(key))
        throw InputError("parameter " + name + ": unknown (config keys: `rgbdmap --list-keys`, " +
                         "'.' written '/'; node settings: ~config, ~out, ~stats, ~map_frame, " +
                         "~camera_frame, ~map_interval, ~map_max_points, ~grid_interval, ~grid, "
                         "~octomap, "
                         "~localise, ~continue, ~session_interval, " +
                         "~session_rate, ~lossless)");
    }
  }
  for (const Key& key : config.keys()) {
    std::string name = key.name;
    for (char& c : name)
      if (c == '.') c = '/';
    XmlRpc::XmlRpcValue value;
    if (!nh.getParam(name, value)) continue;
    const std::string resolved = nh.resolveName(name);
    config.set(key.name, text(value, resolved), "parameter " + resolved);
  }
}

}  // namespace rgbdmap
