#pragma once

#include <opencv2/core.hpp>
#include <opencv2/rgbd.hpp>

#include "rgbdmap/config.hpp"
#include "rgbdmap/pose_provider.hpp"

namespace rgbdmap {

// Camera tracking for sources without ground truth (live cameras, recordings): OpenCV's dense
// RGB-D odometry against the last reference frame, started from a constant-velocity guess.
// Tracking against a reference that is only replaced after enough motion drifts less than
// chaining frame-to-frame estimates. The first frame defines the world frame.
class RgbdOdometryPoses : public PoseProvider {
 public:
  struct Options {
    double min_depth = 0.3;
    double max_depth = 4.0;
    double new_reference_translation = 0.05;  // m
    double new_reference_rotation = 0.0873;   // rad
  };
  RgbdOdometryPoses(const CameraIntrinsics& camera, const Options& options);

  bool estimate(Frame& frame) override;
  std::string describe() const override { return "RGB-D odometry (OpenCV rgbd::RgbdOdometry)"; }
  std::uint64_t failures() const { return failures_; }

 private:
  cv::Ptr<cv::rgbd::OdometryFrame> makeFrame(const Frame& frame);

  Options options_;
  cv::Ptr<cv::rgbd::RgbdOdometry> odometry_;
  cv::Ptr<cv::rgbd::OdometryFrame> reference_;
  Eigen::Isometry3d reference_pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();  // last frame-to-frame motion
  std::uint64_t failures_ = 0;
};

}  // namespace rgbdmap
