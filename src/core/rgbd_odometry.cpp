#include "rgbdmap/rgbd_odometry.hpp"

#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace rgbdmap {

RgbdOdometryPoses::RgbdOdometryPoses(const CameraIntrinsics& camera, const Options& options)
    : options_(options) {
  cv::Mat K;
  cv::Mat(camera.cameraMatrix()).convertTo(K, CV_32F);
  odometry_ = cv::rgbd::RgbdOdometry::create(K, static_cast<float>(options.min_depth),
                                             static_cast<float>(options.max_depth));
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
    return true;
  }
  // Guess: keep moving as in the last frame. Rt maps reference-camera points into the current
  // camera, i.e. the inverse of the current pose relative to the reference.
  const Eigen::Isometry3d guess = reference_pose_.inverse() * last_pose_ * velocity_;
  cv::Mat init, Rt;
  cv::eigen2cv(Eigen::Matrix4d(guess.inverse().matrix()), init);
  if (!odometry_->compute(reference_, current, Rt, init) || Rt.empty()) {
    ++failures_;
    frame.has_pose = false;
    return false;
  }
  Eigen::Matrix4d rt;
  cv::cv2eigen(Rt, rt);
  Eigen::Isometry3d relative(rt);
  const Eigen::Isometry3d pose = reference_pose_ * relative.inverse();
  velocity_ = last_pose_.inverse() * pose;
  last_pose_ = pose;
  frame.pose = pose;
  frame.has_pose = true;

  const Eigen::Isometry3d from_reference = reference_pose_.inverse() * pose;
  if (from_reference.translation().norm() > options_.new_reference_translation ||
      Eigen::AngleAxisd(from_reference.linear()).angle() > options_.new_reference_rotation) {
    reference_ = current;
    reference_pose_ = pose;
  }
  return true;
}

}  // namespace rgbdmap
