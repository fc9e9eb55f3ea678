// The local window of loop closure's graph: a new keyframe aligned densely to the keyframes
// before it, against the exact poses of rendered keyframes.
#include <gtest/gtest.h>

#include <iostream>
#include <opencv2/core/utility.hpp>

#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "rgbdmap/slam/keyframe_window.hpp"
#include "rgbdmap/slam/motion.hpp"

namespace rgbdmap {
namespace {

Eigen::Isometry3d moved(const Eigen::Isometry3d& pose, const Eigen::Vector3d& by, double yaw) {
  Eigen::Isometry3d out = pose;
  out.translation() += by;
  out.linear() = out.linear() * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).matrix();
  return out;
}

class KeyframeWindowTest : public ::testing::Test {
 protected:
  void SetUp() override {
#if defined(__SANITIZE_THREAD__)
    cv::setNumThreads(1);  // the renderer's OpenCV loops run on uninstrumented TBB workers
#endif
    // Four keyframes on the room's walk, 8-9 cm apart, as the tracker spaces them.
    const SyntheticScene scene = SyntheticScene::defaultRoom();
    const SyntheticRenderer renderer(scene, camera_);
    SyntheticSequenceOptions options;
    options.path = "walk";
    const auto path = makeCameraPath(scene, options, options.loop_seconds);
    cv::Mat incidence, hits;
    for (int i = 0; i < 4; ++i) {
      TrackedKeyframe k;
      k.id = static_cast<std::uint64_t>(i);
      k.timestamp = 0.1 * i;
      k.reference = i - 1;
      k.pose = path->pose(k.timestamp);
      renderer.render(k.pose, k.depth, k.color, incidence, hits);
      keyframes_.push_back(k);
    }
  }

  // Feeds the four keyframes with `estimate` as the graph's poses; what the last one measured.
  std::vector<LoopMeasurement> lastMeasured(const LoopOptions& loop,
                                            const std::vector<Eigen::Isometry3d>& estimate) {
    KeyframeWindow window(camera_, TrackingOptions{}, loop, 0.3, 5.0);
    std::vector<LoopMeasurement> out;
    for (const TrackedKeyframe& k : keyframes_)
      out = window.add(k, [&](int id) { return estimate[static_cast<std::size_t>(id)]; });
    return out;
  }

  std::vector<Eigen::Isometry3d> truth() const {
    std::vector<Eigen::Isometry3d> poses;
    for (const TrackedKeyframe& k : keyframes_) poses.push_back(k.pose);
    return poses;
  }

  CameraIntrinsics camera_;  // 640 x 480, f 525
  std::vector<TrackedKeyframe> keyframes_;
};

TEST_F(KeyframeWindowTest, MeasuresTheNewestKeyframeAgainstTheOnesBeforeItsReference) {
  // Odometry put the newest keyframe 4 mm and 0.3 degrees from where it is (within the gate,
  // loop.window_max_change_*).
  std::vector<Eigen::Isometry3d> estimate = truth();
  estimate[3] = moved(estimate[3], {0.003, -0.002, 0.002}, 0.005);
  const std::vector<LoopMeasurement> measured = lastMeasured(LoopOptions{}, estimate);
  // Keyframes 0 and 1; 2 is the one it was tracked against (the tracker's edge).
  ASSERT_EQ(measured.size(), 2u);
  for (const LoopMeasurement& m : measured) {
    EXPECT_EQ(m.later, 3);
    const Eigen::Isometry3d exact =
        keyframes_[static_cast<std::size_t>(m.earlier)].pose.inverse() * keyframes_[3].pose;
    const Eigen::Isometry3d error = exact.inverse() * m.later_in_earlier;
    std::cout << "keyframe " << m.earlier << ": off by " << error.translation().norm() * 1000.0
              << " mm, " << rotationAngle(error) * kDegreesPerRadian << " deg, overlap "
              << m.overlap << "\n";
    EXPECT_LT(error.translation().norm(), 0.002);
    EXPECT_LT(rotationAngle(error), 0.002);
    EXPECT_GT(m.information.trace(), 0.0);
  }
  EXPECT_EQ(measured[0].earlier, 0);
  EXPECT_EQ(measured[1].earlier, 1);
}

TEST_F(KeyframeWindowTest, AnAlignmentThatMovesThePairByCentimetresDoesNotCount) {
  // 2.5 cm off: beyond what odometry drifts over three keyframes (loop.window_max_change_*).
  std::vector<Eigen::Isometry3d> estimate = truth();
  estimate[3] = moved(estimate[3], {0.02, 0.0, 0.015}, 0.0);
  EXPECT_TRUE(lastMeasured(LoopOptions{}, estimate).empty());
  // Allowed that much, the same alignments find the truth.
  LoopOptions loose;
  loose.window_max_change_translation = 0.1;
  EXPECT_EQ(lastMeasured(loose, estimate).size(), 2u);
}

TEST_F(KeyframeWindowTest, HoldsAsManyKeyframesAsConfigured) {
  LoopOptions loop;
  loop.window_keyframes = 2;  // the reference and one before it
  const std::vector<LoopMeasurement> measured = lastMeasured(loop, truth());
  ASSERT_EQ(measured.size(), 1u);
  EXPECT_EQ(measured[0].earlier, 1);
  loop.window_keyframes = 0;  // off
  EXPECT_TRUE(lastMeasured(loop, truth()).empty());
}

}  // namespace
}  // namespace rgbdmap
