#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <optional>
#include <vector>

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap {

// What relocalisation keeps of a keyframe: its grey image and depth until ORB features with 3-D
// points are computed from them (the first time they are needed, so that tracking pays nothing
// for them; the images are let go then).
struct RelocalisationView {
  cv::Mat gray;   // CV_8UC1
  cv::Mat depth;  // CV_32FC1, metres
  bool described = false;
  std::vector<cv::Point3f> points;  // keyframe camera, one per descriptor row
  cv::Mat descriptors;
};

// PnP RANSAC as relocalisation and loop closure run it (EPnP, 200 iterations, 3 pixels): the
// motion mapping `object` points into the camera that saw them at `image` (raw pixels when
// `distorted`, else already undistorted), when at least `min_inliers` agree (`inliers`, if given,
// receives how many did).
std::optional<Eigen::Isometry3d> solvePnp(const std::vector<cv::Point3f>& object,
                                          const std::vector<cv::Point2f>& image,
                                          const CameraIntrinsics& camera, bool distorted,
                                          int min_inliers, int* inliers = nullptr);

// Finds where the camera is relative to a keyframe from ORB feature matches and PnP RANSAC
// (OpenCV), independent of any prior: the way back after tracking was lost.
class Relocaliser {
 public:
  Relocaliser(const CameraIntrinsics& camera, int min_inliers, float min_depth, float max_depth);
  void remember(const Frame& frame, RelocalisationView& view) const;
  // Describes the current image once per call of prepare(); then locate() against keyframes.
  void prepare(const Frame& frame);
  // The prepared image's features with the 3-D points `depth` (of the same frame) gives them, as a
  // keyframe view for later locate() calls: no second feature detection.
  void describePrepared(const cv::Mat& depth, RelocalisationView& view) const;
  // Ratio-test matches between a keyframe and the prepared image: how alike they look.
  int similarity(RelocalisationView& keyframe);
  // The motion mapping keyframe-camera points into the current camera, when enough matches
  // agree on one (`inliers`, if given, receives the PnP inlier count).
  std::optional<Eigen::Isometry3d> locate(RelocalisationView& keyframe, int* inliers = nullptr);
  // The same for a view already described (a place's: shared, never changed).
  int similarity(const RelocalisationView& keyframe);
  std::optional<Eigen::Isometry3d> locate(const RelocalisationView& keyframe,
                                          int* inliers = nullptr);

 private:
  void describe(RelocalisationView& view);
  // Keeps the keypoints with a depth in range, as 3-D points with their descriptor rows.
  void attachPoints(const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& descriptors,
                    const cv::Mat& depth, RelocalisationView& view) const;

  CameraIntrinsics camera_;
  int min_inliers_;
  float min_depth_, max_depth_;
  cv::Ptr<cv::ORB> orb_;
  std::vector<cv::KeyPoint> current_keypoints_;
  cv::Mat current_descriptors_;
};

}  // namespace rgbdmap
