// Keyframe selection: interval, motion and both, on exact camera paths; the default policy per
// pose source; a keyframe that could not be handed over is proposed again.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rgbdmap/config/config.hpp"
#include "rgbdmap/mapping/keyframe_selector.hpp"

namespace rgbdmap {
namespace {

constexpr double kDegree = M_PI / 180.0;

// The frames (by index) a selector makes keyframes of along `path`, each accepted at once.
std::vector<int> keyframesAlong(KeyframeSelector selector,
                                const std::vector<Eigen::Isometry3d>& path) {
  std::vector<int> keyframes;
  for (int i = 0; i < static_cast<int>(path.size()); ++i) {
    if (!selector.wants(path[i])) continue;
    selector.accept(path[i]);
    keyframes.push_back(i);
  }
  return keyframes;
}

std::vector<Eigen::Isometry3d> still(int frames) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(1.0, 0.5, 1.5);
  return std::vector<Eigen::Isometry3d>(static_cast<std::size_t>(frames), pose);
}

// Turning about the vertical (camera y) axis by `step` radians per frame.
std::vector<Eigen::Isometry3d> pan(int frames, double step) {
  std::vector<Eigen::Isometry3d> path;
  for (int i = 0; i < frames; ++i) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::AngleAxisd(step * i, Eigen::Vector3d::UnitY()).toRotationMatrix();
    path.push_back(pose);
  }
  return path;
}

// Moving sideways by `step` metres per frame.
std::vector<Eigen::Isometry3d> slide(int frames, double step) {
  std::vector<Eigen::Isometry3d> path;
  for (int i = 0; i < frames; ++i) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(step * i, 0, 0);
    path.push_back(pose);
  }
  return path;
}

KeyframeSelector selector(KeyframeSelector::Policy policy) {
  KeyframeSelector s;
  s.policy = policy;
  s.every_n = 10;
  s.min_translation = 0.05;
  s.min_rotation = 5 * kDegree;
  return s;
}

TEST(KeyframeSelector, MotionPolicyAddsNothingWhileTheCameraStandsStill) {
  EXPECT_EQ(keyframesAlong(selector(KeyframeSelector::Policy::kMotion), still(300)),
            std::vector<int>{0});
}

TEST(KeyframeSelector, MotionPolicyFollowsAFastPanAtTheConfiguredAngle) {
  // 2 degrees per frame (60 degrees/s at 30 Hz), keyframes every 5 degrees: every 3rd frame.
  const std::vector<int> keyframes =
      keyframesAlong(selector(KeyframeSelector::Policy::kMotion), pan(31, 2 * kDegree));
  EXPECT_EQ(keyframes, (std::vector<int>{0, 3, 6, 9, 12, 15, 18, 21, 24, 27, 30}));
  // Faster than the spacing (8 degrees per frame): every frame.
  EXPECT_EQ(keyframesAlong(selector(KeyframeSelector::Policy::kMotion), pan(6, 8 * kDegree)),
            (std::vector<int>{0, 1, 2, 3, 4, 5}));
}

TEST(KeyframeSelector, MotionPolicyFollowsASlideAtTheConfiguredDistance) {
  // 2 cm per frame, keyframes every 5 cm: every 3rd frame (6 cm).
  EXPECT_EQ(keyframesAlong(selector(KeyframeSelector::Policy::kMotion), slide(10, 0.02)),
            (std::vector<int>{0, 3, 6, 9}));
}

TEST(KeyframeSelector, IntervalPolicyIgnoresMotion) {
  const std::vector<int> every_10{0, 10, 20};
  EXPECT_EQ(keyframesAlong(selector(KeyframeSelector::Policy::kInterval), still(25)), every_10);
  EXPECT_EQ(keyframesAlong(selector(KeyframeSelector::Policy::kInterval), pan(25, 8 * kDegree)),
            every_10);
}

TEST(KeyframeSelector, BothPolicyTakesWhicheverComesFirst) {
  // Still: the interval alone.
  EXPECT_EQ(keyframesAlong(selector(KeyframeSelector::Policy::kBoth), still(25)),
            (std::vector<int>{0, 10, 20}));
  // A pan of 1.2 degrees per frame: motion (6 degrees after 5 frames) comes before the 10th.
  EXPECT_EQ(keyframesAlong(selector(KeyframeSelector::Policy::kBoth), pan(16, 1.2 * kDegree)),
            (std::vector<int>{0, 5, 10, 15}));
  // A slow pan (0.4 degrees per frame): the interval comes first, and restarts the motion count.
  EXPECT_EQ(keyframesAlong(selector(KeyframeSelector::Policy::kBoth), pan(31, 0.4 * kDegree)),
            (std::vector<int>{0, 10, 20, 30}));
}

TEST(KeyframeSelector, AKeyframeNotAcceptedIsProposedAgain) {
  KeyframeSelector s = selector(KeyframeSelector::Policy::kMotion);
  const std::vector<Eigen::Isometry3d> path = pan(8, 2 * kDegree);
  ASSERT_TRUE(s.wants(path[0]));
  s.accept(path[0]);
  EXPECT_FALSE(s.wants(path[1]));
  EXPECT_FALSE(s.wants(path[2]));
  EXPECT_TRUE(s.wants(path[3]));  // fusion busy: not accepted
  EXPECT_TRUE(s.wants(path[4]));  // still due, measured from frame 0
  s.accept(path[4]);
  EXPECT_FALSE(s.wants(path[5]));
  EXPECT_FALSE(s.wants(path[6]));
  EXPECT_TRUE(s.wants(path[7]));

  // The interval counts frames since the last accepted keyframe.
  KeyframeSelector interval = selector(KeyframeSelector::Policy::kInterval);
  const std::vector<Eigen::Isometry3d> rest = still(14);
  interval.accept(rest[0]);
  for (int i = 1; i < 10; ++i) EXPECT_FALSE(interval.wants(rest[i])) << i;
  EXPECT_TRUE(interval.wants(rest[10]));  // not accepted
  EXPECT_TRUE(interval.wants(rest[11]));
  interval.accept(rest[11]);
  EXPECT_FALSE(interval.wants(rest[12]));
}

TEST(KeyframeSelector, DefaultPolicyIsMotionForTrackedCamerasAndIntervalForGivenPoses) {
  Config config;
  EXPECT_EQ(config.keyframe.policy, "auto");
  config.pose.source = "odometry";  // live cameras, recordings, folders without ground truth
  EXPECT_EQ(effectiveKeyframePolicy(config.keyframe, config.pose), "motion");
  EXPECT_EQ(makeKeyframeSelector(config.keyframe, config.pose).policy,
            KeyframeSelector::Policy::kMotion);
  for (const char* source : {"groundtruth", "trajectory"}) {
    config.pose.source = source;
    EXPECT_EQ(effectiveKeyframePolicy(config.keyframe, config.pose), "interval") << source;
  }
  config.keyframe.policy = "both";  // an explicit choice is kept
  config.pose.source = "odometry";
  EXPECT_EQ(makeKeyframeSelector(config.keyframe, config.pose).policy,
            KeyframeSelector::Policy::kBoth);
}

}  // namespace
}  // namespace rgbdmap
