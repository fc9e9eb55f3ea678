// Linked into the `rgbdmap` executable as an object (not through a static library, whose unused
// members the linker would drop): its static initializer adds `rosbag:` to the source factory.
#include "rgbdmap/ros/rosbag_source.hpp"
#include "rgbdmap/runtime/source_factory.hpp"

namespace {

[[maybe_unused]] const bool registered = rgbdmap::registerSourceKind(
    {"rosbag:", "rosbag:FILE.bag",
     [](const std::string& path) { return rgbdmap::presetForBag(path); },
     [](const std::string& path,
        const rgbdmap::Config& config) -> std::unique_ptr<rgbdmap::FrameSource> {
       return std::make_unique<rgbdmap::RosbagSource>(path, config);
     }});

}  // namespace
