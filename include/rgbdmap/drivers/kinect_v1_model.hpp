#pragma once

#include <cstdint>
#include <vector>

namespace rgbdmap {

// The Kinect v1's factory depth model, for raw 11-bit disparity (what libfreenect's
// FREENECT_DEPTH_11BIT and fakenect dumps hold), 640x480:
// - depth z = 1 / (kA * raw + kB) metres (the fit of the factory calibration used with
//   libfreenect), 2047 = no reading; a step of one raw unit is ~3 mm at 1 m, ~2.8 cm at 3 m;
// - the depth (IR) camera sits kBaseline along x from the colour camera with the colour camera's
//   focal length kFocal, so a point at depth z seen at IR column u is at colour column
//   u + kFocal * kBaseline / z (same row). Registration moves each measurement by that shift
//   (the nearer one wins where two land on one pixel); unregistration is its inverse.
// Used by the OpenNI2 Kinect driver (raw -> registered depth) and by `record --format fakenect`
// (depth -> raw), so a dump played through the driver gives back the recorded depth.
class KinectV1Model {
 public:
  static constexpr int kWidth = 640;
  static constexpr int kHeight = 480;
  static constexpr std::uint16_t kNoReading = 2047;
  static constexpr double kA = -0.0030711016;
  static constexpr double kB = 3.3309495161;
  static constexpr double kBaseline = 0.025;  // metres
  static constexpr double kFocal = 525.0;     // pixels

  KinectV1Model();

  // 0 for no reading or a raw value beyond the model's range.
  double metres(std::uint16_t raw) const { return raw < metres_.size() ? metres_[raw] : 0.0; }
  // The raw value whose depth is nearest to `metres`; kNoReading when out of range or not > 0.
  static std::uint16_t raw(double metres);
  // Colour column minus IR column for a raw value (0 for no reading).
  int shift(std::uint16_t raw) const { return raw < shift_.size() ? shift_[raw] : 0; }

  // kWidth x kHeight raw images, row-major: IR view -> colour view and back.
  void registerToColour(const std::uint16_t* ir, std::uint16_t* colour) const;
  void unregisterFromColour(const std::uint16_t* colour, std::uint16_t* ir) const;

 private:
  void move(const std::uint16_t* from, std::uint16_t* to, int direction) const;

  std::vector<double> metres_;  // per raw value
  std::vector<int> shift_;      // per raw value
};

}  // namespace rgbdmap
