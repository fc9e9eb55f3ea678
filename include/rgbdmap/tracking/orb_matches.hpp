#pragma once

#include <opencv2/core.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

namespace rgbdmap {

// Lowe's ratio test on binary descriptors (ORB's, one CV_8U row each): for each row of `query`
// its nearest row of `train` by Hamming distance, kept when it is at most `ratio` times the
// distance of the second nearest (distinctive matches only). The same matches, in the same
// order, as OpenCV's brute-force Hamming knnMatch with k = 2 followed by the test (a tie goes to
// the earlier train row), but without its per-pair call: loop closure compares a new keyframe
// with every remembered place near it, and OpenCV's matcher took about half of that thread's time
// in a room walked twice.
void ratioMatches(const cv::Mat& query, const cv::Mat& train, std::vector<cv::DMatch>& matches,
                  float ratio = 0.8f);

}  // namespace rgbdmap
