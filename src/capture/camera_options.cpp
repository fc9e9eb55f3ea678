#include "rgbdmap/capture/camera_options.hpp"

namespace rgbdmap {

CameraIntrinsics CameraOptions::depthCamera() const {
  CameraIntrinsics depth = *this;
  depth.fx = depth_fx > 0 ? depth_fx : fx;
  depth.fy = depth_fy > 0 ? depth_fy : fy;
  depth.cx = depth_cx != 0 ? depth_cx : cx;
  depth.cy = depth_cy != 0 ? depth_cy : cy;
  if (!depthRegistered()) depth.k1 = depth.k2 = depth.p1 = depth.p2 = depth.k3 = 0;
  return depth;
}

Eigen::Isometry3d CameraOptions::colorFromDepth() const {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d r(depth_rx, depth_ry, depth_rz);
  if (r.norm() > 0) pose.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).matrix();
  pose.translation() = Eigen::Vector3d(depth_x, depth_y, depth_z);
  return pose;
}

Keys cameraKeys(CameraOptions& o) {
  constexpr double kBig = 1e6;
  return {
      integer("camera.width", &o.width, 16, 8192, "image width in pixels"),
      integer("camera.height", &o.height, 16, 8192, "image height in pixels"),
      number("camera.fx", &o.fx, 1, kBig, "focal length x (px)"),
      number("camera.fy", &o.fy, 1, kBig, "focal length y (px)"),
      number("camera.cx", &o.cx, -kBig, kBig, "principal point x (px)"),
      number("camera.cy", &o.cy, -kBig, kBig, "principal point y (px)"),
      number("camera.k1", &o.k1, -100, 100, "radial distortion k1"),
      number("camera.k2", &o.k2, -100, 100, "radial distortion k2"),
      number("camera.p1", &o.p1, -100, 100, "tangential distortion p1"),
      number("camera.p2", &o.p2, -100, 100, "tangential distortion p2"),
      number("camera.k3", &o.k3, -100, 100, "radial distortion k3"),
      number("camera.depth_scale", &o.depth_scale, 1e-3, kBig,
             "depth units per metre (TUM PNG 5000, OpenNI2 1000)"),
      // OpenNI2 sources: where the intrinsics come from.
      choice("camera.intrinsics", &o.intrinsics, {"preset", "device"},
             "preset: camera.fx/fy/cx/cy; device: from the OpenNI2 device's field of view or "
             "the ROS camera_info (used anyway with the default preset and camera keys)"),
      // Unregistered depth (docs/cameras.md#depth-not-registered-to-colour).
      number("camera.depth_fx", &o.depth_fx, 0, kBig,
             "depth camera's focal length x (px; 0 = the colour camera's)"),
      number("camera.depth_fy", &o.depth_fy, 0, kBig,
             "depth camera's focal length y (px; 0 = the colour camera's)"),
      number("camera.depth_cx", &o.depth_cx, -kBig, kBig,
             "depth camera's principal point x (px; 0 = the colour camera's)"),
      number("camera.depth_cy", &o.depth_cy, -kBig, kBig,
             "depth camera's principal point y (px; 0 = the colour camera's)"),
      number("camera.depth_x", &o.depth_x, -1, 1,
             "depth camera's position in the colour camera's frame, x (m; 0 = registered)"),
      number("camera.depth_y", &o.depth_y, -1, 1, "depth camera's position, y (m)"),
      number("camera.depth_z", &o.depth_z, -1, 1, "depth camera's position, z (m)"),
      number("camera.depth_rx", &o.depth_rx, -0.5, 0.5,
             "depth camera's rotation in the colour camera's frame, rotation vector x (rad)"),
      number("camera.depth_ry", &o.depth_ry, -0.5, 0.5, "depth camera's rotation vector, y (rad)"),
      number("camera.depth_rz", &o.depth_rz, -0.5, 0.5, "depth camera's rotation vector, z (rad)"),
  };
}

}  // namespace rgbdmap
