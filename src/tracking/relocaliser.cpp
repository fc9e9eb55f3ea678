#include "rgbdmap/tracking/relocaliser.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/base/image_buffer_pool.hpp"
#include "rgbdmap/capture/lens_undistortion.hpp"
#include "rgbdmap/tracking/orb_matches.hpp"

namespace rgbdmap {

Relocaliser::Relocaliser(const CameraIntrinsics& camera, int min_inliers, float min_depth,
                         float max_depth)
    : camera_(camera),
      min_inliers_(min_inliers),
      min_depth_(min_depth),
      max_depth_(max_depth),
      orb_(cv::ORB::create(800)) {}

void Relocaliser::remember(const Frame& frame, RelocalisationView& view) const {
  view.gray = pooledImage(frame.color.rows, frame.color.cols, CV_8UC1);
  cv::cvtColor(frame.color, view.gray, cv::COLOR_BGR2GRAY);
  view.depth = pooledCopy(frame.depth);
  view.described = false;
  view.points.clear();
  view.descriptors.release();
}

void Relocaliser::describe(RelocalisationView& view) {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  orb_->detectAndCompute(view.gray, cv::noArray(), keypoints, descriptors);
  attachPoints(keypoints, descriptors, view.depth, view);
  view.gray.release();
  view.depth.release();
}

void Relocaliser::attachPoints(const std::vector<cv::KeyPoint>& keypoints,
                               const cv::Mat& descriptors, const cv::Mat& depth,
                               RelocalisationView& view) const {
  std::vector<cv::Point2f> pixels;
  std::vector<int> rows;
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const cv::Point2f& p = keypoints[i].pt;
    const float z = depth.at<float>(cvRound(p.y), cvRound(p.x));
    if (!(z >= min_depth_ && z <= max_depth_)) continue;
    pixels.push_back(p);
    rows.push_back(static_cast<int>(i));
  }
  view.points.clear();
  view.descriptors.release();
  if (!pixels.empty()) {
    // Rays through the undistorted pixel positions (the lens distorts the image, not depth).
    std::vector<cv::Point2f> rays;
    LensUndistortion::rays(camera_, pixels, rays);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const float z = depth.at<float>(cvRound(pixels[i].y), cvRound(pixels[i].x));
      view.points.emplace_back(rays[i].x * z, rays[i].y * z, z);
      view.descriptors.push_back(descriptors.row(rows[i]));
    }
  }
  view.described = true;
}

void Relocaliser::prepare(const Frame& frame) {
  cv::Mat gray;
  cv::cvtColor(frame.color, gray, cv::COLOR_BGR2GRAY);
  current_keypoints_.clear();
  orb_->detectAndCompute(gray, cv::noArray(), current_keypoints_, current_descriptors_);
}

void Relocaliser::describePrepared(const cv::Mat& depth, RelocalisationView& view) const {
  view.gray.release();
  view.depth.release();
  attachPoints(current_keypoints_, current_descriptors_, depth, view);
}

int Relocaliser::similarity(RelocalisationView& keyframe) {
  if (!keyframe.described) describe(keyframe);
  return similarity(static_cast<const RelocalisationView&>(keyframe));
}

int Relocaliser::similarity(const RelocalisationView& keyframe) {
  std::vector<cv::DMatch> matches;
  ratioMatches(keyframe.descriptors, current_descriptors_, matches);
  return static_cast<int>(matches.size());
}

std::optional<Eigen::Isometry3d> Relocaliser::locate(RelocalisationView& keyframe, int* inliers) {
  if (!keyframe.described) describe(keyframe);
  return locate(static_cast<const RelocalisationView&>(keyframe), inliers);
}

std::optional<Eigen::Isometry3d> Relocaliser::locate(const RelocalisationView& keyframe,
                                                     int* inliers) {
  if (keyframe.descriptors.rows < min_inliers_ || current_descriptors_.rows < min_inliers_)
    return std::nullopt;
  std::vector<cv::DMatch> matches;
  ratioMatches(keyframe.descriptors, current_descriptors_, matches);
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (const cv::DMatch& m : matches) {
    object.push_back(keyframe.points[static_cast<std::size_t>(m.queryIdx)]);
    image.push_back(current_keypoints_[static_cast<std::size_t>(m.trainIdx)].pt);
  }
  return solvePnp(object, image, camera_, true, min_inliers_, inliers);
}

std::optional<Eigen::Isometry3d> solvePnp(const std::vector<cv::Point3f>& object,
                                          const std::vector<cv::Point2f>& image,
                                          const CameraIntrinsics& camera, bool distorted,
                                          int min_inliers, int* inliers) {
  if (static_cast<int>(object.size()) < min_inliers) return std::nullopt;
  cv::Mat rvec, tvec;
  std::vector<int> inlier_rows;
  const cv::Mat distortion = distorted ? cv::Mat(camera.distortion()) : cv::Mat();
  if (!cv::solvePnPRansac(object, image, camera.cameraMatrix(), distortion, rvec, tvec, false, 200,
                          3.0f, 0.99, inlier_rows, cv::SOLVEPNP_EPNP) ||
      static_cast<int>(inlier_rows.size()) < min_inliers)
    return std::nullopt;
  if (inliers) *inliers = static_cast<int>(inlier_rows.size());
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  cv::cv2eigen(R, r);
  cv::cv2eigen(tvec, t);
  if (!r.allFinite() || !t.allFinite()) return std::nullopt;
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = r;
  motion.translation() = t;
  return motion;
}

}  // namespace rgbdmap
