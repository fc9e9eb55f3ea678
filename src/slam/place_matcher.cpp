#include "rgbdmap/slam/place_matcher.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/tracking/orb_matches.hpp"
#include "rgbdmap/tracking/relocaliser.hpp"

namespace rgbdmap {
namespace {

// A reference level's points drawn into its image: each point's intensity and depth spread over
// its four nearest pixels by bilinear weights (a place seen from elsewhere does not fall on pixel
// centres), among the points nearest the camera there. `drawn`: 1 where a pixel got enough of
// some point, else 0 (and 0 grey and depth).
void drawPoints(const AlignmentReference::Level& level, cv::Mat& gray, cv::Mat& depth,
                cv::Mat& drawn) {
  const LevelCamera& c = level.camera;
  const auto pixelOf = [&c](const Eigen::Vector4f& p, float& u, float& v) {
    if (!(p.z() > 0.0f)) return false;
    u = c.fx * p.x() / p.z() + c.cx;
    v = c.fy * p.y() / p.z() + c.cy;
    return u >= 0.0f && v >= 0.0f && u <= static_cast<float>(c.width - 1) &&
           v <= static_cast<float>(c.height - 1);
  };
  cv::Mat nearest(c.height, c.width, CV_32FC1, cv::Scalar(0));
  float u = 0, v = 0;
  for (const Eigen::Vector4f& p : level.points) {
    if (!pixelOf(p, u, v)) continue;
    float& z =
        nearest.at<float>(static_cast<int>(std::lround(v)), static_cast<int>(std::lround(u)));
    if (z == 0.0f || p.z() < z) z = p.z();
  }
  gray = cv::Mat(c.height, c.width, CV_32FC1, cv::Scalar(0));
  depth = cv::Mat(c.height, c.width, CV_32FC1, cv::Scalar(0));
  drawn = cv::Mat(c.height, c.width, CV_32FC1, cv::Scalar(0));
  for (const Eigen::Vector4f& p : level.points) {
    if (!pixelOf(p, u, v)) continue;
    const int x0 = std::min(static_cast<int>(u), c.width - 2),
              y0 = std::min(static_cast<int>(v), c.height - 2);
    const float fx = u - static_cast<float>(x0), fy = v - static_cast<float>(y0);
    const float weights[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    for (int k = 0; k < 4; ++k) {
      const int x = x0 + (k & 1), y = y0 + (k >> 1);
      const float z = nearest.at<float>(y, x);
      if (weights[k] <= 0.0f || (z > 0.0f && p.z() > 1.05f * z)) continue;  // hidden there
      gray.at<float>(y, x) += weights[k] * p.w();
      depth.at<float>(y, x) += weights[k] * p.z();
      drawn.at<float>(y, x) += weights[k];
    }
  }
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) {
      float& w = drawn.at<float>(y, x);
      if (w < 0.05f) {  // too little of any point to say
        gray.at<float>(y, x) = depth.at<float>(y, x) = w = 0.0f;
        continue;
      }
      gray.at<float>(y, x) /= w;
      depth.at<float>(y, x) /= w;
      w = 1.0f;
    }
}

// The pixels not drawn take the mean grey of their drawn neighbours, ring after ring, until every
// pixel has one: flat pixels (the reference keeps every other row and column of them) are what
// their neighbours are, and a point that lands where nothing was drawn still finds an intensity.
void fillFromNeighbours(cv::Mat& gray, cv::Mat& drawn) {
  cv::Mat sum, count;
  for (int ring = 0; ring < gray.cols + gray.rows &&
                     static_cast<std::size_t>(cv::countNonZero(drawn)) < gray.total();
       ++ring) {
    cv::boxFilter(gray, sum, -1, cv::Size(3, 3), cv::Point(-1, -1), false);
    cv::boxFilter(drawn, count, -1, cv::Size(3, 3), cv::Point(-1, -1), false);
    for (int y = 0; y < gray.rows; ++y) {
      float* g = gray.ptr<float>(y);
      float* d = drawn.ptr<float>(y);
      const float* s = sum.ptr<float>(y);
      const float* n = count.ptr<float>(y);
      for (int x = 0; x < gray.cols; ++x)
        if (d[x] == 0.0f && n[x] > 0.0f) {
          g[x] = s[x] / n[x];
          d[x] = 1.0f;
        }
    }
  }
}

// The view a place was made from, as the dense aligner samples a frame (a place keeps no
// image): its reference's finest level drawn and filled, then levels finest+1..levels-1 halved
// from it (depth only where drawn). False: nothing to draw.
bool drawView(const AlignmentReference& reference, int finest, int levels, ImagePyramid& out) {
  if (finest >= static_cast<int>(reference.levels.size())) return false;
  const AlignmentReference::Level& level = reference.levels[static_cast<std::size_t>(finest)];
  if (level.points.empty() || level.camera.width < 4 || level.camera.height < 4) return false;
  cv::Mat gray, depth, drawn;
  drawPoints(level, gray, depth, drawn);
  fillFromNeighbours(gray, drawn);
  out.buildFromLevel(gray, depth, level.camera, finest, levels);
  return true;
}

}  // namespace

PlaceMatcher::PlaceMatcher(const CameraIntrinsics& camera, const TrackingOptions& tracking,
                           const LoopOptions& loop)
    : camera_(camera),
      tracking_(loopVerificationOptions(tracking, loop)),
      loop_(loop),
      aligner_(tracking_) {}

int PlaceMatcher::similarity(const PlaceRecognition::Place& a,
                             const PlaceRecognition::Place& b) const {
  std::vector<cv::DMatch> matches;
  ratioMatches(a.view.descriptors, b.view.descriptors, matches);
  return static_cast<int>(matches.size());
}

std::optional<LoopMeasurement> PlaceMatcher::match(const PlaceRecognition::Place& candidate,
                                                   const PlaceRecognition::Place& query) {
  std::vector<cv::DMatch> matches;
  ratioMatches(candidate.view.descriptors, query.view.descriptors, matches);
  if (static_cast<int>(matches.size()) < loop_.min_matches) return std::nullopt;
  // PnP: the candidate's 3-D points against where the query saw its own (projected).
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (const cv::DMatch& m : matches) {
    const cv::Point3f& q = query.view.points[static_cast<std::size_t>(m.trainIdx)];
    if (!(q.z > 0.0f)) continue;
    object.push_back(candidate.view.points[static_cast<std::size_t>(m.queryIdx)]);
    image.emplace_back(static_cast<float>(camera_.fx * q.x / q.z + camera_.cx),
                       static_cast<float>(camera_.fy * q.y / q.z + camera_.cy));
  }
  int inliers = 0;
  const std::optional<Eigen::Isometry3d> candidate_in_query =
      solvePnp(object, image, camera_, false, loop_.min_inliers, &inliers);
  if (!candidate_in_query) return std::nullopt;
  // (Only places the camera has really been back to, as loop closure's.)
  if (candidate_in_query->translation().norm() > loop_.max_distance) return std::nullopt;
  AlignmentReference target, seen;
  candidate.reference.expand(target);
  query.reference.expand(seen);
  ImagePyramid view;
  if (!drawView(seen, tracking_.finest_level, tracking_.coarsest_level + 1, view))
    return std::nullopt;
  std::optional<LoopMeasurement> loop = verifiedLoop(
      aligner_.align(target, view, *candidate_in_query), *candidate_in_query, tracking_, loop_);
  if (!loop) return std::nullopt;
  loop->matches = static_cast<int>(matches.size());
  loop->inliers = inliers;
  return loop;
}

}  // namespace rgbdmap
