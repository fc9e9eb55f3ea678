#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <optional>
#include <vector>

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap {

// What relocalisation keeps of a keyframe: its grey image and depth, and (computed the first time
// they are needed, so that tracking pays nothing for them) ORB features with 3-D points.
struct RelocalisationView {
  cv::Mat gray;   // CV_8UC1
  cv::Mat depth;  // CV_32FC1, metres
  bool described = false;
  std::vector<cv::Point3f> points;  // keyframe camera, one per descriptor row
  cv::Mat descriptors;
};

// Finds where the camera is relative to a keyframe from ORB feature matches and PnP RANSAC
// (OpenCV), independent of any prior: the way back after tracking was lost.
class Relocaliser {
 public:
  Relocaliser(const CameraIntrinsics& camera, int min_inliers, float min_depth, float max_depth);
  void remember(const Frame& frame, RelocalisationView& view) const;
  // Describes the current image once per call of prepare(); then locate() against keyframes.
  void prepare(const Frame& frame);
  // The motion mapping keyframe-camera points into the current camera, when enough matches
  // agree on one.
  std::optional<Eigen::Isometry3d> locate(RelocalisationView& keyframe);

 private:
  void describe(RelocalisationView& view);

  CameraIntrinsics camera_;
  int min_inliers_;
  float min_depth_, max_depth_;
  cv::Ptr<cv::ORB> orb_;
  cv::Ptr<cv::DescriptorMatcher> matcher_;
  std::vector<cv::KeyPoint> current_keypoints_;
  cv::Mat current_descriptors_;
};

}  // namespace rgbdmap
