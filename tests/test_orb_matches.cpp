// The ratio-test matcher of relocalisation and loop closure gives what OpenCV's brute-force
// Hamming matcher gives (knnMatch with k = 2, then the ratio test): the same pairs in the same
// order, on ORB features of real frames and on descriptors built to tie.

#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "rgbdmap/tracking/orb_matches.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

std::vector<cv::DMatch> opencvRatioMatches(const cv::Mat& query, const cv::Mat& train,
                                           float ratio) {
  std::vector<cv::DMatch> out;
  if (query.rows < 2 || train.rows < 2) return out;
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_HAMMING).knnMatch(query, train, knn, 2);
  for (const auto& m : knn)
    if (m.size() == 2 && m[0].distance <= ratio * m[1].distance) out.push_back(m[0]);
  return out;
}

void expectSameMatches(const std::vector<cv::DMatch>& expected,
                       const std::vector<cv::DMatch>& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(expected[i].queryIdx, actual[i].queryIdx) << i;
    EXPECT_EQ(expected[i].trainIdx, actual[i].trainIdx) << i;
    EXPECT_EQ(expected[i].distance, actual[i].distance) << i;
  }
}

cv::Mat orbOf(const std::string& path) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  EXPECT_FALSE(image.empty()) << path;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  cv::ORB::create(800)->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
  return descriptors;
}

TEST(OrbMatches, AsOpenCvMatchesOnRealFrames) {
  const std::string rgb = test::tumDir(test::kXyz) + "/rgb/";
  const cv::Mat a = orbOf(rgb + "1305031102.175304.png");
  const cv::Mat b = orbOf(rgb + "1305031102.243211.png");
  ASSERT_GT(a.rows, 300);
  ASSERT_GT(b.rows, 300);
  for (const float ratio : {0.8f, 0.6f, 1.0f}) {
    std::vector<cv::DMatch> ours;
    ratioMatches(a, b, ours, ratio);
    expectSameMatches(opencvRatioMatches(a, b, ratio), ours);
    if (ratio == 0.8f) {
      EXPECT_GT(ours.size(), 100u);  // two frames 70 ms apart look alike
    }
  }
}

TEST(OrbMatches, TiesGoToTheEarlierRowAsOpenCvs) {
  // Descriptors with only a few bits set, so that many distances tie; one row of 32 bytes (ORB)
  // and rows of a length that is not a whole number of 64-bit words.
  std::mt19937 random(7);
  for (const int bytes : {32, 13}) {
    cv::Mat query(60, bytes, CV_8UC1, cv::Scalar(0)), train(80, bytes, CV_8UC1, cv::Scalar(0));
    for (cv::Mat* m : {&query, &train})
      for (int r = 0; r < m->rows; ++r)
        for (int k = 0; k < 3; ++k)
          m->at<std::uint8_t>(r, static_cast<int>(random() % static_cast<unsigned>(bytes))) |=
              static_cast<std::uint8_t>(1u << (random() % 8));
    train.row(5).copyTo(train.row(40));  // an exact duplicate: the first of the two wins
    query.row(3).copyTo(train.row(5));
    std::vector<cv::DMatch> ours;
    ratioMatches(query, train, ours, 1.0f);
    expectSameMatches(opencvRatioMatches(query, train, 1.0f), ours);
    ASSERT_FALSE(ours.empty());
  }
}

TEST(OrbMatches, TooFewRowsMatchNothing) {
  const cv::Mat one(1, 32, CV_8UC1, cv::Scalar(3)), many(10, 32, CV_8UC1, cv::Scalar(3));
  std::vector<cv::DMatch> matches{cv::DMatch(0, 0, 1.0f)};
  ratioMatches(one, many, matches);
  EXPECT_TRUE(matches.empty());
  ratioMatches(many, one, matches);
  EXPECT_TRUE(matches.empty());
}

}  // namespace
}  // namespace rgbdmap
