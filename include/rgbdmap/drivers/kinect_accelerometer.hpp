#pragma once

#include <cstdint>

namespace rgbdmap {

// The Kinect v1's accelerometer (a KXSD9 in the tilt motor's housing, 819 counts per g), as the
// project's OpenNI2 Kinect driver offers it and `record --format fakenect` writes it.
//
// Axes: libfreenect's freenect_get_mks_accel, which are also those of TUM's accelerometer.txt
// (recorded from the same register through the same conversion): at rest it reads gravity's
// reaction, so AccelerometerLog::upInCamera turns a sample into the camera's up.
struct KinectAcceleration {
  double x = 0;  // m/s²
  double y = 0;
  double z = 0;

  static constexpr double kCountsPerG = 819.0;
  static constexpr double kGravity = 9.80665;

  static KinectAcceleration fromCounts(std::int16_t x, std::int16_t y, std::int16_t z) {
    constexpr double scale = kGravity / kCountsPerG;
    return {x * scale, y * scale, z * scale};
  }
};

// OpenNI2 device property (Device::getProperty) holding the latest KinectAcceleration; only the
// Kinect driver supports it, and only when the tilt motor's USB device could be opened. Outside
// OpenNI2's own and PrimeSense's property ranges.
constexpr int kKinectAccelerationProperty = 0x4B563141;  // "KV1A"

// libfreenect's freenect_raw_tilt_state as fakenect reads it from an accelerometer dump file
// ('a' records: the struct's bytes on x86-64 Linux, 12 bytes with padding).
struct FakenectTiltState {
  std::int16_t accelerometer_x = 0;
  std::int16_t accelerometer_y = 0;
  std::int16_t accelerometer_z = 0;
  std::int8_t tilt_angle = 0;
  std::int32_t tilt_status = 0;  // an enum in libfreenect.h
};
static_assert(sizeof(FakenectTiltState) == 12, "must match freenect_raw_tilt_state");

}  // namespace rgbdmap
