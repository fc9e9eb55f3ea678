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
  // Depth from a camera of its own (not registered to the colour one): its intrinsics (0: the
  // colour camera's) and its pose in the colour camera's frame (translation in m, rotation vector
  // in rad). All zero: depth is registered to colour, as TUM's and OpenNI2's registered mode are.
  double depth_fx = 0, depth_fy = 0, depth_cx = 0, depth_cy = 0;
  double depth_x = 0, depth_y = 0, depth_z = 0;
  double depth_rx = 0, depth_ry = 0, depth_rz = 0;

  bool depthRegistered() const {
    return depth_fx == 0 && depth_fy == 0 && depth_cx == 0 && depth_cy == 0 && depth_x == 0 &&
           depth_y == 0 && depth_z == 0 && depth_rx == 0 && depth_ry == 0 && depth_rz == 0;
  }
  // The depth camera's intrinsics: its own where the keys give them, the colour camera's
  // otherwise. A depth camera of its own is an ideal pinhole; registered depth shares the colour
  // lens.
  CameraIntrinsics depthCamera() const;
  // The depth camera's pose in the colour camera's frame (identity when registered).
  Eigen::Isometry3d colorFromDepth() const;
};

Keys cameraKeys(CameraOptions& o);

}  // namespace rgbdmap
