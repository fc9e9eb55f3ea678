#include "rgbdmap/tracking/rgbd_odometry.hpp"

#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace rgbdmap {

RgbdOdometryPoses::RgbdOdometryPoses(const CameraIntrinsics& camera, const Options& options)
    : options_(options) {
  cv::Mat K;
  cv::Mat(camera.cameraMatrix()).convertTo(K, CV_32F);
  const float min_depth = static_cast<float>(options.min_depth);
  const float max_depth = static_cast<float>(options.max_depth);
  if (options.icp)
    odometry_ = cv::rgbd::RgbdICPOdometry::create(K, min_depth, max_depth);
  else
    odometry_ = cv::rgbd::RgbdOdometry::create(K, min_depth, max_depth);
}

cv::Ptr<cv::rgbd::OdometryFrame> RgbdOdometryPoses::makeFrame(const Frame& frame) {
  cv::Mat gray, depth;
  cv::cvtColor(frame.color, gray, cv::COLOR_BGR2GRAY);
  frame.depth.copyTo(depth);
  cv::Mat mask = (depth > options_.min_depth) & (depth < options_.max_depth);
  return cv::rgbd::OdometryFrame::create(gray, depth, mask);
}

bool RgbdOdometryPoses::estimate(Frame& frame) {
  cv::Ptr<cv::rgbd::OdometryFrame> current = makeFrame(frame);
  if (!reference_) {
    reference_ = current;
    reference_pose_ = last_pose_ = Eigen::Isometry3d::Identity();
    frame.pose = last_pose_;
    frame.has_pose = true;
    state_ = TrackingState::kTracked;
    return true;
  }
  // Guess: keep moving as in the last frame. Rt maps reference-camera points into the current
  // camera, i.e. the inverse of the current pose relative to the reference.
  const Eigen::Isometry3d guess = reference_pose_.inverse() * last_pose_ * velocity_;
  cv::Mat init, Rt;
  cv::eigen2cv(Eigen::Matrix4d(guess.inverse().matrix()), init);
  const Eigen::Isometry3d predicted = last_pose_ * velocity_;
  std::optional<Eigen::Isometry3d> relative;
  if (odometry_->compute(reference_, current, Rt, init) && !Rt.empty())
    relative = plausible(Rt, guess);
  if (!relative) {
    // Lost: this frame is not mapped. Tracking restarts from it at the predicted pose, so the
    // next frame is aligned to a near image instead of a reference it can no longer match.
    ++failures_;
    reference_ = current;
    reference_pose_ = last_pose_ = predicted;
    frame.pose = predicted;
    frame.has_pose = false;
    state_ = TrackingState::kLost;
    return false;
  }
  const Eigen::Isometry3d pose = reference_pose_ * relative->inverse();
  velocity_ = last_pose_.inverse() * pose;
  last_pose_ = pose;
  frame.pose = pose;
  frame.has_pose = true;
  state_ = state_ == TrackingState::kLost ? TrackingState::kRelocalised : TrackingState::kTracked;

  const Eigen::Isometry3d from_reference = reference_pose_.inverse() * pose;
  if (from_reference.translation().norm() > options_.new_reference_translation ||
      Eigen::AngleAxisd(from_reference.linear()).angle() > options_.new_reference_rotation) {
    reference_ = current;
    reference_pose_ = pose;
  }
  return true;
}

std::optional<Eigen::Isometry3d> RgbdOdometryPoses::plausible(
    const cv::Mat& Rt, const Eigen::Isometry3d& guess) const {
  Eigen::Matrix4d rt;
  cv::cv2eigen(Rt, rt);
  if (!rt.allFinite()) return std::nullopt;
  const Eigen::Matrix3d r = rt.topLeftCorner<3, 3>();
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3)
    return std::nullopt;
  Eigen::Isometry3d relative = Eigen::Isometry3d::Identity();
  // Re-orthonormalised, so rounding does not accumulate into a non-rigid pose over many frames.
  relative.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
  relative.translation() = rt.topRightCorner<3, 1>();
  // guess places the current camera in the reference frame; relative is its estimated inverse.
  const Eigen::Isometry3d jump = guess.inverse() * relative.inverse();
  if (jump.translation().norm() > options_.max_jump_translation ||
      Eigen::AngleAxisd(jump.linear()).angle() > options_.max_jump_rotation)
    return std::nullopt;
  return relative;
}

}  // namespace rgbdmap
