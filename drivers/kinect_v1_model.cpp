#include "rgbdmap/drivers/kinect_v1_model.hpp"

#include <cmath>

namespace rgbdmap {

KinectV1Model::KinectV1Model() : metres_(kNoReading + 1, 0.0), shift_(kNoReading + 1, 0) {
  for (int raw = 0; raw < kNoReading; ++raw) {
    const double inverse = kA * raw + kB;
    if (inverse <= 0) break;  // beyond infinity: no reading
    metres_[raw] = 1.0 / inverse;
    shift_[raw] = static_cast<int>(std::lround(kFocal * kBaseline * inverse));
  }
}

std::uint16_t KinectV1Model::raw(double metres) {
  if (!(metres > 0) || !std::isfinite(metres)) return kNoReading;
  const double value = std::round((1.0 / metres - kB) / kA);
  if (value < 0 || value >= kNoReading) return kNoReading;
  // The model is monotonic: a measurement beyond the last representable raw value is dropped.
  if (kA * value + kB <= 0) return kNoReading;
  return static_cast<std::uint16_t>(value);
}

void KinectV1Model::registerToColour(const std::uint16_t* ir, std::uint16_t* colour) const {
  move(ir, colour, +1);
}

void KinectV1Model::unregisterFromColour(const std::uint16_t* colour, std::uint16_t* ir) const {
  move(colour, ir, -1);
}

// Smaller raw values are nearer (z grows with raw), so they win a pixel.
void KinectV1Model::move(const std::uint16_t* from, std::uint16_t* to, int direction) const {
  for (int i = 0; i < kWidth * kHeight; ++i) to[i] = kNoReading;
  for (int y = 0; y < kHeight; ++y) {
    const std::uint16_t* in = from + y * kWidth;
    std::uint16_t* out = to + y * kWidth;
    for (int x = 0; x < kWidth; ++x) {
      const std::uint16_t raw = in[x];
      if (raw >= kNoReading || metres_[raw] <= 0) continue;
      const int target = x + direction * shift_[raw];
      if (target < 0 || target >= kWidth) continue;
      if (raw < out[target]) out[target] = raw;
    }
  }
}

}  // namespace rgbdmap
