#pragma once

#include <string>

namespace rgbdmap {

// The pose.source a run uses, given the one asked for (the key's value) and whether its source
// has ground truth poses: "auto" becomes "groundtruth" when it has them, else "odometry"; the
// other values stay. Ground truth asked of a source without it throws InputError with `refusal`
// (each front door says how its users set the key).
std::string resolvePoseSource(const std::string& requested, bool source_has_poses,
                              const std::string& refusal);

}  // namespace rgbdmap
