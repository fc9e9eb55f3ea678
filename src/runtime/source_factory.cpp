#include "rgbdmap/runtime/source_factory.hpp"

#include <vector>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_names.hpp"
#include "rgbdmap/capture/tum_source.hpp"
#include "rgbdmap/drivers/openni2_source.hpp"

namespace rgbdmap {
namespace {

// Filled by static initializers before main(), read-only afterwards: no lock needed. A function
// static, so that it exists whichever initializer runs first.
std::vector<SourceKind>& registeredKinds() {
  static std::vector<SourceKind> kinds;
  return kinds;
}

const SourceKind* registeredKind(const std::string& spec) {
  for (const SourceKind& kind : registeredKinds())
    if (spec.rfind(kind.prefix, 0) == 0) return &kind;
  return nullptr;
}

}  // namespace

bool registerSourceKind(SourceKind kind) {
  registeredKinds().push_back(std::move(kind));
  return true;
}

std::string sourceUsage() {
  std::string usage = "tum:DIR, openni2, openni2:URI, openni2:FILE.oni";
  for (const SourceKind& kind : registeredKinds()) usage += ", " + kind.usage;
  return usage;
}

std::string presetForSource(const std::string& spec) {
  if (spec.rfind("tum:", 0) == 0) {
    const std::string preset = TumSequence::presetForFolder(spec.substr(4));
    return preset.empty() ? "default" : preset;
  }
  if (spec.rfind("openni2:tum:", 0) == 0) {
    // A TUM folder through the OpenNI2 driver: the folder's camera (options after '?' aside).
    const std::string uri = spec.substr(12);
    const std::string preset = TumSequence::presetForFolder(uri.substr(0, uri.find('?')));
    return preset.empty() ? "default" : preset;
  }
  if (spec == "openni2" || spec.rfind("openni2:", 0) == 0) {
    const std::string uri = spec == "openni2" ? "" : spec.substr(8);
    if (endsWith(uri, ".oni")) return "kinect_v1";  // a recording
    const std::string model = openNI2CameraModel(uri);
    return model.empty() ? "kinect_v1" : model;
  }
  if (const SourceKind* kind = registeredKind(spec)) {
    const std::string preset = kind->preset(spec.substr(kind->prefix.size()));
    return preset.empty() ? "default" : preset;
  }
  return "default";
}

std::unique_ptr<FrameSource> openSource(const std::string& spec, const Config& config) {
  if (spec.rfind("tum:", 0) == 0) {
    TumSequence::Options options;
    options.depth_scale = config.camera.depth_scale;
    options.max_pose_gap = config.pose.max_gap;
    return std::make_unique<TumSource>(spec.substr(4), options, config.camera, config.replay.rate);
  }
  if (spec == "openni2") return openOpenNI2Source("", config.camera, config.replay.rate);
  if (spec.rfind("openni2:", 0) == 0)
    return openOpenNI2Source(spec.substr(8), config.camera, config.replay.rate);
  if (const SourceKind* kind = registeredKind(spec))
    return kind->open(spec.substr(kind->prefix.size()), config);
  throw InputError("--source " + spec + ": unknown source (expected " + sourceUsage() + ")");
}

}  // namespace rgbdmap
