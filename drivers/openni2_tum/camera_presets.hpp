#pragma once

#include <string>

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap::openni2_tum {

// Intrinsics of the camera that recorded a TUM folder: freiburg1/2/3 from the folder name
// (rgbd_dataset_freiburgN_...), otherwise the PrimeSense default. They are the camera sections
// of config/tum_fr*.yaml and config/default.yaml, compiled in because an installed plugin has
// no source tree to read them from (tests check the two stay equal).
CameraIntrinsics intrinsicsForFolder(const std::string& folder);

// Full field of view in radians along one image axis of `size` pixels with focal length
// `focal` (pixels): the inverse of f = size / (2 tan(fov / 2)), which is how OpenNI2 programs
// turn ONI_STREAM_PROPERTY_HORIZONTAL_FOV / VERTICAL_FOV back into focal lengths.
double fieldOfView(int size, double focal);

}  // namespace rgbdmap::openni2_tum
