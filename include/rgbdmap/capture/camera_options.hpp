#pragma once

#include <string>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/option_keys.hpp"

namespace rgbdmap {

// The camera of a run (config section "camera"): its intrinsics, how its depth is scaled and,
// for sources that can tell (OpenNI2 devices, ROS camera_info), whether theirs are used instead.
struct CameraOptions : CameraIntrinsics {
  double depth_scale = 5000.0;  // depth units per metre (TUM 5000)
  // "preset" (the camera.fx/fy/cx/cy above) or "device" (from the field of view an OpenNI2
  // device reports; other sources ignore it).
  std::string intrinsics = "preset";
};

Keys cameraKeys(CameraOptions& o);

}  // namespace rgbdmap
