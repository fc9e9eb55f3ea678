#include "rgbdmap/tools/map_renderer.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/base/file_names.hpp"
#include "rgbdmap/base/image_file.hpp"
#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/map_files/ply_file.hpp"

namespace rgbdmap {
namespace {

// Where the virtual camera stands: looking along the mean camera direction of
// the trajectory (or the cloud's least-spread axis when there is none), pulled
// back so the map fits.
Eigen::Isometry3d chooseView(const MapCloud& cloud, const Trajectory& trajectory, double fov) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : cloud) centroid += p.getVector3fMap().cast<double>();
  centroid /= static_cast<double>(std::max<std::size_t>(cloud.size(), 1));

  Eigen::Vector3d forward(0, 0, 1), down(0, 1, 0);
  if (!trajectory.empty()) {
    Eigen::Vector3d f = Eigen::Vector3d::Zero(), d = Eigen::Vector3d::Zero();
    for (const StampedPose& p : trajectory.poses()) {
      f += p.pose.linear().col(2);
      d += p.pose.linear().col(1);
    }
    if (f.norm() > 1e-6) forward = f.normalized();
    if (d.norm() > 1e-6) down = d.normalized();
  }
  // Look slightly downwards onto the scene: tilt forward towards "down".
  forward = (forward + 0.25 * down).normalized();
  down = (down - down.dot(forward) * forward);
  down = down.norm() > 1e-6 ? down.normalized() : forward.unitOrthogonal();
  const Eigen::Vector3d right = down.cross(forward).normalized();

  // Distance that fits the cloud's spread (95th percentile radius) into the
  // field of view.
  std::vector<double> radii;
  radii.reserve(cloud.size());
  for (const auto& p : cloud)
    radii.push_back((p.getVector3fMap().cast<double>() - centroid).norm());
  double radius = 1.0;
  if (!radii.empty()) {
    const std::size_t k = radii.size() * 95 / 100;
    std::nth_element(radii.begin(), radii.begin() + static_cast<long>(k), radii.end());
    radius = std::max(radii[k], 0.1);
  }
  const double distance = radius / std::tan(fov * M_PI / 360.0) * 1.1;

  Eigen::Isometry3d view = Eigen::Isometry3d::Identity();
  view.linear().col(0) = right;
  view.linear().col(1) = down;
  view.linear().col(2) = forward;
  view.translation() = centroid - distance * forward;
  return view;
}

}  // namespace

cv::Mat MapRenderer::render(const MapCloud& cloud, const Trajectory& trajectory) const {
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(40, 40, 40));
  cv::Mat zbuffer(height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  const Eigen::Isometry3d view = chooseView(cloud, trajectory, fov_degrees);
  const Eigen::Isometry3d world_to_view = view.inverse();
  const double f = 0.5 * width / std::tan(fov_degrees * M_PI / 360.0);
  const double cx = 0.5 * width, cy = 0.5 * height;
  auto project = [&](const Eigen::Vector3d& w, cv::Point2d& px, double& z) {
    const Eigen::Vector3d c = world_to_view * w;
    if (c.z() <= 0.05) return false;
    px = {f * c.x() / c.z() + cx, f * c.y() / c.z() + cy};
    z = c.z();
    return true;
  };
  for (const auto& p : cloud) {
    cv::Point2d px;
    double z;
    if (!project(p.getVector3fMap().cast<double>(), px, z)) continue;
    const int u0 = static_cast<int>(std::lround(px.x)), v0 = static_cast<int>(std::lround(px.y));
    for (int v = v0 - point_radius; v <= v0 + point_radius; ++v) {
      if (v < 0 || v >= height) continue;
      for (int u = u0 - point_radius; u <= u0 + point_radius; ++u) {
        if (u < 0 || u >= width) continue;
        float& depth = zbuffer.at<float>(v, u);
        if (z >= depth) continue;
        depth = static_cast<float>(z);
        image.at<cv::Vec3b>(v, u) = cv::Vec3b(p.b, p.g, p.r);
      }
    }
  }
  for (std::size_t i = 1; i < trajectory.size(); ++i) {
    cv::Point2d a, b;
    double za, zb;
    if (project(trajectory[i - 1].pose.translation(), a, za) &&
        project(trajectory[i].pose.translation(), b, zb))
      cv::line(image, a, b, cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
  }
  cv::putText(image, std::to_string(cloud.size()) + " points", {12, height - 14},
              cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  return image;
}

cv::Mat MapRenderer::render(const TriangleMesh& mesh, const Trajectory& trajectory) const {
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(40, 40, 40));
  cv::Mat zbuffer(height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  MapCloud corners;  // the view is chosen as for the vertices as a cloud
  corners.resize(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    corners[i].getVector3fMap() = mesh.vertices[i];
  const Eigen::Isometry3d view = chooseView(corners, trajectory, fov_degrees);
  const Eigen::Isometry3d world_to_view = view.inverse();
  const double f = 0.5 * width / std::tan(fov_degrees * M_PI / 360.0);
  const double cx = 0.5 * width, cy = 0.5 * height;
  std::vector<Eigen::Vector3d> camera(mesh.vertices.size());  // in the view's frame
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    camera[i] = world_to_view * mesh.vertices[i].cast<double>();
  for (const TriangleMesh::Triangle& t : mesh.triangles) {
    const Eigen::Vector3d &a = camera[t[0]], &b = camera[t[1]], &c = camera[t[2]];
    if (a.z() <= 0.05 || b.z() <= 0.05 || c.z() <= 0.05) continue;  // no clipping: dropped
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    if (normal.norm() < 1e-12) continue;
    const double shade = 0.3 + 0.7 * std::abs(normal.normalized().dot(a.normalized()));
    double u[3], v[3];
    const Eigen::Vector3d* corner[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
      u[k] = f * corner[k]->x() / corner[k]->z() + cx;
      v[k] = f * corner[k]->y() / corner[k]->z() + cy;
    }
    const double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    if (std::abs(area) < 1e-12) continue;
    const int u0 = std::max(0, static_cast<int>(std::floor(std::min({u[0], u[1], u[2]}))));
    const int u1 = std::min(width - 1, static_cast<int>(std::ceil(std::max({u[0], u[1], u[2]}))));
    const int v0 = std::max(0, static_cast<int>(std::floor(std::min({v[0], v[1], v[2]}))));
    const int v1 = std::min(height - 1, static_cast<int>(std::ceil(std::max({v[0], v[1], v[2]}))));
    for (int y = v0; y <= v1; ++y) {
      for (int x = u0; x <= u1; ++x) {
        const double px = x + 0.5, py = y + 0.5;  // pixel centres, barycentric weights:
        const double w0 = ((u[1] - px) * (v[2] - py) - (u[2] - px) * (v[1] - py)) / area;
        const double w1 = ((u[2] - px) * (v[0] - py) - (u[0] - px) * (v[2] - py)) / area;
        const double w2 = 1.0 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const float z = static_cast<float>(w0 * a.z() + w1 * b.z() + w2 * c.z());
        float& depth = zbuffer.at<float>(y, x);
        if (z >= depth) continue;
        depth = z;
        cv::Vec3b& out = image.at<cv::Vec3b>(y, x);
        for (int channel = 0; channel < 3; ++channel) {  // BGR from RGB
          const double mixed = w0 * mesh.colours[t[0]][2 - channel] +
                               w1 * mesh.colours[t[1]][2 - channel] +
                               w2 * mesh.colours[t[2]][2 - channel];
          out[channel] = cv::saturate_cast<std::uint8_t>(mixed * shade);
        }
      }
    }
  }
  for (std::size_t i = 1; i < trajectory.size(); ++i) {
    const Eigen::Vector3d p = world_to_view * trajectory[i - 1].pose.translation();
    const Eigen::Vector3d q = world_to_view * trajectory[i].pose.translation();
    if (p.z() > 0.05 && q.z() > 0.05)
      cv::line(image, cv::Point2d(f * p.x() / p.z() + cx, f * p.y() / p.z() + cy),
               cv::Point2d(f * q.x() / q.z() + cx, f * q.y() / q.z() + cy), cv::Scalar(0, 0, 255),
               2, cv::LINE_AA);
  }
  cv::putText(image, std::to_string(mesh.triangles.size()) + " triangles", {12, height - 14},
              cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  return image;
}

bool renderMapFile(const std::string& map_path, const std::string& trajectory_path,
                   const std::string& png_path, const MapRenderer& renderer, std::string& error) {
  MapCloud cloud;
  TriangleMesh mesh;
  try {
    // A binary PLY with faces (--mesh) is a mesh; anything else is read as points.
    if (endsWith(map_path, ".ply")) mesh = readPly(map_path);
  } catch (const std::exception&) {
    mesh = TriangleMesh();  // e.g. an ASCII PLY: PCL's reader below says what is wrong
  }
  if (mesh.empty()) {
    try {
      cloud = loadMapFile(map_path);  // checks the header first: PCL crashes on some garbage
    } catch (const std::exception& e) {
      error = e.what();
      return false;
    }
  }
  Trajectory trajectory;
  if (!trajectory_path.empty() && pathExists(trajectory_path)) {
    try {
      trajectory = Trajectory::load(trajectory_path);
    } catch (const std::exception& e) {
      error = e.what();
      return false;
    }
  }
  try {
    const cv::Mat image =
        mesh.empty() ? renderer.render(cloud, trajectory) : renderer.render(mesh, trajectory);
    if (!writeImageFile(png_path, image, error)) return false;
  } catch (const cv::Exception& e) {
    error = png_path + ": cannot write image (" + e.err + ")";
    return false;
  }
  return true;
}

}  // namespace rgbdmap
