#pragma once

#include <memory>
#include <string>

#include "rgbdmap/base/config.hpp"
#include "rgbdmap/capture/frame_source.hpp"

namespace rgbdmap {

// The preset a source spec implies when no --config is given: tum_frN from a TUM folder name,
// "default" otherwise.
std::string presetForSource(const std::string& spec);

// Opens a source from its spec: "tum:DIR", "openni2", "openni2:URI" or "openni2:FILE.oni".
// Throws InputError with what is wrong (missing folder, no camera, ...).
std::unique_ptr<FrameSource> openSource(const std::string& spec, const Config& config);

}  // namespace rgbdmap
