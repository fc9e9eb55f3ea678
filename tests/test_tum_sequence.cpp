// Association and ground-truth interpolation against hand-checked rows of the real TUM lists.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "rgbdmap/capture/association.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using test::kRpy;
using test::kXyz;

TEST(Association, FollowsTumsGreedyRule) {
  // Candidates by difference: (a1,b0) 0.002, (a0,b0) 0.008, (a1,b1) 0.015. The closest pair is
  // taken first, so a0 loses b0 to a1 and a1 cannot take b1 any more: one pair only.
  const std::vector<double> a = {1.000, 1.010, 2.000};
  const std::vector<double> b = {1.008, 1.025, 3.000};
  const auto pairs = associate(a, b, 0.02);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0], std::make_pair(std::size_t{1}, std::size_t{0}));
  // Output is sorted by the first list's stamps.
  const auto sorted = associate({2.0, 1.0}, {1.001, 2.001}, 0.02);
  ASSERT_EQ(sorted.size(), 2u);
  EXPECT_EQ(sorted[0], std::make_pair(std::size_t{1}, std::size_t{0}));  // stamp 1.0 first
  EXPECT_EQ(sorted[1], std::make_pair(std::size_t{0}, std::size_t{1}));
}

TEST(Association, RespectsOffsetAndStrictWindow) {
  EXPECT_TRUE(associate({1.0}, {1.02}, 0.02).empty());  // strictly less than max_difference
  EXPECT_EQ(associate({1.0}, {0.95}, 0.02, 0.05).size(), 1u);
}

TEST(TumSequence, AssociatesFr1XyzLikeAssociatePy) {
  const TumSequence seq(test::tumDir(kXyz));
  // 37 colour and 37 depth images; TUM's associate.py pairs 32 of them.
  ASSERT_EQ(seq.size(), 32u);
  EXPECT_EQ(seq.unmatchedColor(), 5u);
  EXPECT_EQ(seq.unmatchedDepth(), 5u);
  // Hand-checked: rgb.txt line 4 (1305031102.175304) pairs with depth.txt line 4
  // (1305031102.160407, 14.9 ms) rather than line 5 (1305031102.194330, 19.0 ms).
  EXPECT_DOUBLE_EQ(seq[0].rgb_time, 1305031102.175304);
  EXPECT_DOUBLE_EQ(seq[0].depth_time, 1305031102.160407);
  EXPECT_EQ(seq[0].rgb_line, 4u);
  EXPECT_EQ(seq[0].depth_line, 4u);
  // The colour image 1305031102.243211 (line 6) finds no partner left: 1305031102.226738 went to
  // 1305031102.211214 (15.5 ms) and 1305031102.262886 to 1305031102.275326 (12.4 ms).
  for (std::size_t i = 0; i < seq.size(); ++i) EXPECT_NE(seq[i].rgb_time, 1305031102.243211);
  EXPECT_DOUBLE_EQ(seq[1].rgb_time, 1305031102.211214);
  EXPECT_DOUBLE_EQ(seq[1].depth_time, 1305031102.226738);
  // Last pair: the last lines of both files.
  EXPECT_DOUBLE_EQ(seq[31].rgb_time, 1305031103.375327);
  EXPECT_DOUBLE_EQ(seq[31].depth_time, 1305031103.362405);
}

TEST(TumSequence, InterpolatesGroundTruthAtColourStamp) {
  const TumSequence seq(test::tumDir(kXyz));
  ASSERT_TRUE(seq[0].pose.has_value());
  // groundtruth.txt lines 354-355: 1305031102.1658 (1.3434 0.6271 1.6606) and 1305031102.1758
  // (1.3405 0.6266 1.6575); s = (0.175304 - 0.1658) / 0.01 = 0.9504.
  const double s = 0.9504;
  const Eigen::Vector3d expected(1.3434 + s * (1.3405 - 1.3434), 0.6271 + s * (0.6266 - 0.6271),
                                 1.6606 + s * (1.6575 - 1.6606));
  // Stamps near 1.3e9 s carry ~1e-7 s of rounding: 1e-6 m is far below any real error.
  EXPECT_LT((seq[0].pose->translation() - expected).norm(), 1e-6);
  // Rotation: between the two samples' quaternions (slerp), so close to both.
  const Eigen::Quaterniond qa(-0.3266, 0.6583, 0.6112, -0.2938),
      qb(-0.3248, 0.6574, 0.6126, -0.2949);
  const Eigen::Quaterniond q(seq[0].pose->linear());
  EXPECT_LT(q.angularDistance(qb.normalized()), q.angularDistance(qa.normalized()) + 1e-12);
  EXPECT_LT(q.angularDistance(qb.normalized()), 1e-3);
  EXPECT_EQ(seq.framesWithoutPose(), 0u);
}

TEST(TumSequence, FramesFarFromGroundTruthGetNoPose) {
  Trajectory gt({{10.0, Eigen::Isometry3d::Identity()}, {10.2, Eigen::Isometry3d::Identity()}});
  EXPECT_FALSE(gt.interpolate(10.1, 0.05).has_value());  // both neighbours 0.1 s away
  EXPECT_TRUE(gt.interpolate(10.1, 0.15).has_value());
  EXPECT_FALSE(gt.interpolate(9.99).has_value());  // before the first sample
  EXPECT_TRUE(gt.interpolate(10.2).has_value());   // exactly on the last sample
}

TEST(TumSequence, Rpy100HasEveryColourFrame) {
  const TumSequence seq(test::tumDir(kRpy));
  EXPECT_EQ(seq.size(), 100u);  // 100 colour, 101 depth images
  EXPECT_EQ(seq.unmatchedDepth(), 1u);
  EXPECT_EQ(seq.framesWithoutPose(), 0u);
}

TEST(TumSequence, LoadsDepthInMetresAndColour) {
  TumSequence seq(test::tumDir(kXyz));
  Frame frame;
  std::string error;
  ASSERT_TRUE(seq.load(0, frame, error)) << error;
  const cv::Mat raw = cv::imread(seq[0].depth_path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1);
  ASSERT_EQ(frame.depth.type(), CV_32FC1);
  ASSERT_EQ(frame.color.type(), CV_8UC3);
  int checked = 0;
  for (int v = 0; v < raw.rows; v += 37)
    for (int u = 0; u < raw.cols; u += 41) {
      EXPECT_FLOAT_EQ(frame.depth.at<float>(v, u), raw.at<std::uint16_t>(v, u) / 5000.0f);
      ++checked;
    }
  EXPECT_GT(checked, 100);
  EXPECT_DOUBLE_EQ(frame.timestamp, seq[0].rgb_time);
  EXPECT_TRUE(frame.has_pose);
}

TEST(TumSequence, PresetFromFolderName) {
  EXPECT_EQ(TumSequence::presetForFolder("/data/rgbd_dataset_freiburg1_xyz/"), "tum_fr1");
  EXPECT_EQ(TumSequence::presetForFolder("rgbd_dataset_freiburg3_long_office_household"),
            "tum_fr3");
  EXPECT_EQ(TumSequence::presetForFolder("/tmp/freiburg2/synthetic_room"), "");
}

}  // namespace
}  // namespace rgbdmap
