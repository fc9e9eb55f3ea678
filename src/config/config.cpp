#include "rgbdmap/config/config.hpp"

namespace rgbdmap {

Keys Config::keys() {
  Keys keys = cameraKeys(camera);
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
