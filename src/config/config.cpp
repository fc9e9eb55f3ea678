#include "rgbdmap/config/config.hpp"

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {

Keys Config::keys() {
  Keys keys = cameraKeys(camera);
  // One key for the lens, read by tracking (its pyramid, relocalisation, places) and by fusion:
  // each layer keeps its own flag, both set by it. Its former names (two keys) are still read.
  Key lens = boolean("camera.undistort", &tracking.undistort,
                     "undo the lens distortion (camera.k1-k3, p1, p2) in tracking, relocalisation "
                     "and fusion");
  lens.set = [set = lens.set, this](const std::string& value) {
    set(value);
    filter.undistort = tracking.undistort;
  };
  keys.push_back(lens);
  keys.push_back(formerName("tracking.undistort", lens));
  keys.push_back(formerName("filter.undistort", lens));
  keys.push_back(number("camera.readout", &tracking.readout, 0, 0.1,
                        "rolling shutter: seconds from reading the image's first row to its last, "
                        "undone in tracking with the camera's motion (0 = global shutter)"));
  append(keys, replayKeys(replay));
  append(keys, queueKeys(queue));
  append(keys, poseKeys(pose));
  append(keys, trackingKeys(tracking));
  append(keys, loopKeys(loop));
  append(keys, refusionKeys(refusion));
  append(keys, keyframeKeys(keyframe));
  append(keys, filterKeys(filter));
  append(keys, mapKeys(map));
  append(keys, checkpointKeys(checkpoint));
  append(keys, upKeys(up));
  append(keys, gridKeys(grid));
  append(keys, octomapKeys(octomap));
  return sections.insertInto(std::move(keys));
}

void Config::set(const std::string& key, const std::string& value, const std::string& origin) {
  Keys all = keys();
  setKey(all, key, value, origin);
}

void Config::setAll(const std::vector<std::string>& assignments, const std::string& origin) {
  for (const std::string& s : assignments) {
    const auto eq = s.find('=');
    if (eq == std::string::npos) throw InputError(origin + " " + s + ": expected key=value");
    set(s.substr(0, eq), s.substr(eq + 1), origin);
  }
}

void Config::loadYaml(const std::string& path) {
  Keys all = keys();
  loadYamlKeys(all, path, preset);
}

void Config::loadPreset(const std::string& name_or_path) {
  const std::string path = presetPath(name_or_path);
  preset = name_or_path;
  loadYaml(path);
}

std::string Config::toYaml() { return keysToYaml(keys(), preset); }

}  // namespace rgbdmap
