#pragma once

#include <opencv2/core.hpp>
#include <opencv2/rgbd.hpp>
#include <optional>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"

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
    // An estimate this far from the constant-velocity guess is a divergence, not motion: a
    // hand-held camera at 30 fps does not change its speed by 0.15 m/frame or turn 20° more.
    double max_jump_translation = 0.15;  // m
    double max_jump_rotation = 0.35;     // rad
    bool icp = false;  // RgbdICPOdometry (depth only, point-to-plane) instead of RgbdOdometry
  };
  RgbdOdometryPoses(const CameraIntrinsics& camera, const Options& options);

  bool estimate(Frame& frame) override;
  std::string describe() const override {
    return options_.icp ? "RGB-D odometry (OpenCV rgbd::RgbdICPOdometry)"
                        : "RGB-D odometry (OpenCV rgbd::RgbdOdometry)";
  }
  TrackingState state() const override { return state_; }
  std::uint64_t failures() const { return failures_; }

 private:
  cv::Ptr<cv::rgbd::OdometryFrame> makeFrame(const Frame& frame);
  // The estimate as a rigid motion, or nothing when it is not one or jumps away from the guess.
  std::optional<Eigen::Isometry3d> plausible(const cv::Mat& Rt,
                                             const Eigen::Isometry3d& guess) const;

  Options options_;
  cv::Ptr<cv::rgbd::Odometry> odometry_;
  cv::Ptr<cv::rgbd::OdometryFrame> reference_;
  Eigen::Isometry3d reference_pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();  // last frame-to-frame motion
  std::uint64_t failures_ = 0;
  TrackingState state_ = TrackingState::kNoPose;
};

}  // namespace rgbdmap
