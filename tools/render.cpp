#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <sys/stat.h>

#include <Eigen/Eigenvalues>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/tools/commands.hpp"
#include "rgbdmap/tools/map_renderer.hpp"

namespace rgbdmap {
namespace {

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

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

bool renderMapFile(const std::string& map_path, const std::string& trajectory_path,
                   const std::string& png_path, const MapRenderer& renderer, std::string& error) {
  MapCloud cloud;
  try {
    cloud = loadMapFile(map_path);  // checks the header first: PCL crashes on some garbage
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
  Trajectory trajectory;
  if (!trajectory_path.empty() && exists(trajectory_path)) {
    try {
      trajectory = Trajectory::load(trajectory_path);
    } catch (const std::exception& e) {
      error = e.what();
      return false;
    }
  }
  try {
    if (!cv::imwrite(png_path, renderer.render(cloud, trajectory))) {
      error = png_path + ": cannot write image";
      return false;
    }
  } catch (const cv::Exception& e) {
    error = png_path + ": cannot write image (" + e.err + ")";
    return false;
  }
  return true;
}

void addRenderCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand("render", "render a map (PCD/PLY) to a PNG picture, headless");
  struct Options {
    std::string map, trajectory, out;
    MapRenderer renderer;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("map", o->map, "map file (.pcd or .ply)")->required();
  cmd->add_option("-o,--out", o->out, "PNG to write (default: the map's name with .png)");
  cmd->add_option("-t,--trajectory", o->trajectory, "TUM trajectory to draw and to place the view");
  cmd->add_option("--width", o->renderer.width, "image width")->check(CLI::Range(64, 8192));
  cmd->add_option("--height", o->renderer.height, "image height")->check(CLI::Range(64, 8192));
  cmd->add_option("--point-radius", o->renderer.point_radius, "splat radius (px)")
      ->check(CLI::Range(0, 10));
  cmd->callback([o, &selected] {
    selected = [o] {
      const std::string out =
          o->out.empty() ? o->map.substr(0, o->map.find_last_of('.')) + ".png" : o->out;
      std::string error;
      if (!renderMapFile(o->map, o->trajectory, out, o->renderer, error)) {
        std::fprintf(stderr, "rgbdmap render: %s\n", error.c_str());
        return 1;
      }
      std::printf("%s\n", out.c_str());
      return 0;
    };
  });
}

}  // namespace rgbdmap
