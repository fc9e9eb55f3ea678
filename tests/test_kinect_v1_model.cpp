// The Kinect v1 factory depth model shared by `record --format fakenect` and the OpenNI2 Kinect
// driver: raw disparity <-> metres, and registration to colour and back.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rgbdmap/drivers/kinect_v1_model.hpp"

namespace rgbdmap {
namespace {

TEST(KinectV1Model, RawDisparityRoundTripsWithinHalfAStep) {
  const KinectV1Model model;
  for (double z = 0.4; z < 8.0; z += 0.0137) {
    const std::uint16_t raw = KinectV1Model::raw(z);
    ASSERT_LT(raw, KinectV1Model::kNoReading) << z;
    const double step = -KinectV1Model::kA * z * z;  // metres per raw unit at z
    EXPECT_NEAR(model.metres(raw), z, 0.55 * step) << z;
    EXPECT_EQ(KinectV1Model::raw(model.metres(raw)), raw) << z;
  }
  // About 3 mm per raw step at 1 m.
  EXPECT_NEAR(model.metres(KinectV1Model::raw(1.0)) - model.metres(KinectV1Model::raw(1.0) - 1),
              0.003, 0.0005);
  EXPECT_EQ(KinectV1Model::raw(0), KinectV1Model::kNoReading);
  EXPECT_EQ(KinectV1Model::raw(-1), KinectV1Model::kNoReading);
  EXPECT_EQ(KinectV1Model::raw(NAN), KinectV1Model::kNoReading);
  EXPECT_EQ(KinectV1Model::raw(0.1), KinectV1Model::kNoReading);  // nearer than the Kinect sees
  EXPECT_EQ(model.metres(KinectV1Model::kNoReading), 0.0);
}

TEST(KinectV1Model, RegistrationShiftsByBaselineOverDepthAndUndoesUnregistration) {
  const KinectV1Model model;
  constexpr int w = KinectV1Model::kWidth, h = KinectV1Model::kHeight;
  // A wall at 2 m with a box at 1 m in front of it.
  std::vector<std::uint16_t> colour(w * h), ir(w * h), back(w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      colour[y * w + x] = KinectV1Model::raw(x > 200 && x < 300 && y > 100 && y < 200 ? 1.0 : 2.0);
  const int shift_1m = model.shift(KinectV1Model::raw(1.0));
  EXPECT_NEAR(shift_1m, KinectV1Model::kFocal * KinectV1Model::kBaseline / 1.0, 1.0);
  model.unregisterFromColour(colour.data(), ir.data());
  EXPECT_EQ(ir[150 * w + 250 - shift_1m], colour[150 * w + 250]);
  model.registerToColour(ir.data(), back.data());
  std::size_t same = 0, lost = 0;
  for (int i = 0; i < w * h; ++i) {
    same += back[i] == colour[i];
    lost += back[i] == KinectV1Model::kNoReading;
  }
  // Only the edges the box hides from the other camera, and the image border, are lost.
  EXPECT_EQ(same + lost, static_cast<std::size_t>(w * h));
  EXPECT_LT(lost, static_cast<std::size_t>(h * 2 * shift_1m));
}

}  // namespace
}  // namespace rgbdmap
