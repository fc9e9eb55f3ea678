#pragma once

namespace rgbdmap {

// Kinect v1 depth noise (Nguyen, Izadi, Lovell 2012): axial sigma in metres at depth z,
// kBase + kGrowth * (z - kFrom)^2. The coefficients are named so that vector code (fusion),
// which cannot call this function, uses the same model.
struct KinectNoise {
  static constexpr float kBase = 0.0012f;    // m
  static constexpr float kGrowth = 0.0019f;  // 1/m
  static constexpr float kFrom = 0.4f;       // m
};
inline float kinectDepthSigma(float z) {
  const float d = z - KinectNoise::kFrom;
  return KinectNoise::kBase + KinectNoise::kGrowth * d * d;
}

}  // namespace rgbdmap
