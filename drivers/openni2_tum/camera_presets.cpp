#include "camera_presets.hpp"

#include <cmath>

#include "rgbdmap/capture/tum_sequence.hpp"

namespace rgbdmap::openni2_tum {
namespace {

CameraIntrinsics makeIntrinsics(double fx, double fy, double cx, double cy, double k1, double k2,
                                double p1, double p2, double k3) {
  CameraIntrinsics camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = fx;
  camera.fy = fy;
  camera.cx = cx;
  camera.cy = cy;
  camera.k1 = k1;
  camera.k2 = k2;
  camera.p1 = p1;
  camera.p2 = p2;
  camera.k3 = k3;
  return camera;
}

}  // namespace

CameraIntrinsics intrinsicsForFolder(const std::string& folder) {
  const std::string preset = TumSequence::presetForFolder(folder);
  if (preset == "tum_fr1")
    return makeIntrinsics(517.3, 516.5, 318.6, 255.3, 0.2624, -0.9531, -0.0054, 0.0026, 1.1633);
  if (preset == "tum_fr2")
    return makeIntrinsics(520.9, 521.0, 325.1, 249.7, 0.2312, -0.7849, -0.0033, -0.0001, 0.9172);
  if (preset == "tum_fr3") return makeIntrinsics(535.4, 539.2, 320.1, 247.6, 0, 0, 0, 0, 0);
  return makeIntrinsics(525.0, 525.0, 319.5, 239.5, 0, 0, 0, 0, 0);
}

double fieldOfView(int size, double focal) { return 2.0 * std::atan(size / (2.0 * focal)); }

}  // namespace rgbdmap::openni2_tum
