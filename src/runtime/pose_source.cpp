#include "rgbdmap/runtime/pose_source.hpp"

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {

std::string resolvePoseSource(const std::string& requested, bool source_has_poses,
                              const std::string& refusal) {
  if (requested == "auto") return source_has_poses ? "groundtruth" : "odometry";
  if (requested == "groundtruth" && !source_has_poses) throw InputError(refusal);
  return requested;
}

}  // namespace rgbdmap
