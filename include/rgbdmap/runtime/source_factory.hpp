#pragma once

#include <functional>
#include <memory>
#include <string>

#include "rgbdmap/capture/frame_source.hpp"
#include "rgbdmap/config/config.hpp"

namespace rgbdmap {

// The preset a source spec implies when no --config is given: tum_frN from a TUM folder name,
// "default" otherwise.
std::string presetForSource(const std::string& spec);

// Opens a source from its spec: "tum:DIR", "openni2", "openni2:URI" or "openni2:FILE.oni", or a
// registered kind ("rosbag:FILE.bag"). Throws InputError with what is wrong (missing folder, no
// camera, ...).
std::unique_ptr<FrameSource> openSource(const std::string& spec, const Config& config);

// The source specs this build understands, for help and error messages.
std::string sourceUsage();

// Adapters at the edge (ROS) add source kinds without the core knowing them: an adapter library
// registers "prefix:" from a static initializer in an object linked into the executable.
struct SourceKind {
  std::string prefix;  // "rosbag:"
  std::string usage;   // "rosbag:FILE.bag"
  // The preset implied by what follows the prefix ("" = default).
  std::function<std::string(const std::string& rest)> preset;
  std::function<std::unique_ptr<FrameSource>(const std::string& rest, const Config& config)> open;
};
// Returns true so that it can initialise a static.
bool registerSourceKind(SourceKind kind);

}  // namespace rgbdmap
