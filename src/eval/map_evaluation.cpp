#include "rgbdmap/eval/map_evaluation.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/kdtree/kdtree_flann.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_names.hpp"

namespace rgbdmap {
namespace {

// Reads a PCD or PLY file generically (PCL's typed loaders misbehave on empty clouds) and
// checks it has coordinates.
pcl::PCLPointCloud2 loadCloudBlob(const std::string& path, const char* what) {
  if (!isFile(path)) throw InputError(path + ": no such file (" + what + ")");
  pcl::PCLPointCloud2 blob;
  int result = -1;
  // PCL's readers throw on some malformed headers (a number that is not one): a bad file, not
  // a crash (found by fuzz/fuzz_map_file).
  try {
    if (endsWithIgnoringCase(path, ".ply")) {
      result = pcl::io::loadPLYFile(path, blob);
    } else if (endsWithIgnoringCase(path, ".pcd")) {
      // PCL 1.13's reader crashes on a file whose header declares no fields, so the header is
      // checked first; a header with no points is an empty cloud.
      pcl::PCDReader reader;
      Eigen::Vector4f origin;
      Eigen::Quaternionf orientation;
      int version = 0, data_type = 0;
      unsigned int data_index = 0;
      if (reader.readHeader(path, blob, origin, orientation, version, data_type, data_index) < 0 ||
          blob.fields.empty())
        throw InputError(path + ": not a PCD file (no valid header with FIELDS)");
      if (blob.width * blob.height == 0) return blob;
      result = reader.read(path, blob);
    } else {
      throw InputError(path + ": unknown point cloud format (expected .pcd or .ply)");
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path + ": not a valid " + std::string(what) + " (" + e.what() + ")");
  }
  if (result < 0) throw InputError(path + ": cannot read the " + std::string(what));
  bool x = false, y = false, z = false;
  for (const pcl::PCLPointField& field : blob.fields) {
    x |= field.name == "x";
    y |= field.name == "y";
    z |= field.name == "z";
  }
  if (!(x && y && z) && blob.width * blob.height > 0)
    throw InputError(path + ": the " + std::string(what) + " has no x, y, z fields");
  // PCL's conversion to a typed cloud copies each field with the size of the point type's field
  // (4 bytes for x, y, z, rgb): a header that declares other sizes, fields beyond the point, or
  // less data than it promises would make it read out of bounds (found by fuzz_map_file).
  for (const pcl::PCLPointField& field : blob.fields) {
    const std::size_t bytes =
        pcl::getFieldSize(field.datatype) * std::max<std::size_t>(field.count, 1);
    const bool copied = field.name == "x" || field.name == "y" || field.name == "z" ||
                        field.name == "rgb" || field.name == "rgba";
    if ((copied && pcl::getFieldSize(field.datatype) != 4) ||
        field.offset + bytes > blob.point_step)
      throw InputError(path + ": field " + field.name + " of the " + std::string(what) +
                       " has a size or offset that does not fit its points");
  }
  if (blob.data.size() < std::size_t(blob.point_step) * blob.width * blob.height)
    throw InputError(path + ": the " + std::string(what) + " holds less data than its header says");
  return blob;
}

double quantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  const std::size_t k =
      std::min(values.size() - 1, static_cast<std::size_t>(q * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}

}  // namespace

std::string MapScore::toJson() const {
  char text[1024];
  std::snprintf(text, sizeof(text),
                "{\n  \"tau_m\": %.6f,\n  \"map_points\": %zu,\n  \"reference_points\": %zu,\n"
                "  \"precision\": %.6f,\n  \"recall\": %.6f,\n  \"f_score\": %.6f,\n"
                "  \"mean_distance_m\": %.6f,\n  \"median_distance_m\": %.6f,\n"
                "  \"p95_distance_m\": %.6f,\n  \"mean_distance_mm\": %.3f,\n"
                "  \"median_distance_mm\": %.3f,\n  \"p95_distance_mm\": %.3f\n}\n",
                tau, map_points, reference_points, precision, recall, f_score, mean_distance,
                median_distance, p95_distance, 1000.0 * mean_distance, 1000.0 * median_distance,
                1000.0 * p95_distance);
  return text;
}

MapScore evaluateMap(const pcl::PointCloud<pcl::PointXYZRGB>& map, const SyntheticScene& scene,
                     const pcl::PointCloud<pcl::PointXYZ>& reference, double tau) {
  MapScore score;
  score.tau = tau;
  auto points = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  points->reserve(map.size());
  std::vector<double> distances;
  distances.reserve(map.size());
  for (const pcl::PointXYZRGB& p : map) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    points->push_back(pcl::PointXYZ(p.x, p.y, p.z));
    distances.push_back(scene.distance(Eigen::Vector3d(p.x, p.y, p.z)));
  }
  score.map_points = points->size();
  score.reference_points = reference.size();
  if (!distances.empty()) {
    double sum = 0.0;
    std::size_t close = 0;
    for (const double d : distances) {
      sum += d;
      if (d <= tau) ++close;
    }
    score.precision = static_cast<double>(close) / static_cast<double>(distances.size());
    score.mean_distance = sum / static_cast<double>(distances.size());
    score.median_distance = quantile(distances, 0.5);
    score.p95_distance = quantile(distances, 0.95);
  }
  if (!points->empty() && !reference.empty()) {
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(points);
    std::vector<int> index(1);
    std::vector<float> squared(1);
    std::size_t covered = 0;
    const float tau_squared = static_cast<float>(tau * tau);
    for (const pcl::PointXYZ& r : reference) {
      if (tree.nearestKSearch(r, 1, index, squared) == 1 && squared[0] <= tau_squared) ++covered;
    }
    score.recall = static_cast<double>(covered) / static_cast<double>(reference.size());
  }
  if (score.precision + score.recall > 0.0)
    score.f_score = 2.0 * score.precision * score.recall / (score.precision + score.recall);
  return score;
}

pcl::PointCloud<pcl::PointXYZRGB> loadMapFile(const std::string& path) {
  const pcl::PCLPointCloud2 blob = loadCloudBlob(path, "map");
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  if (blob.width * blob.height > 0) pcl::fromPCLPointCloud2(blob, cloud);
  return cloud;
}

SyntheticGroundTruth loadSyntheticGroundTruth(const std::string& folder_or_scene) {
  std::string folder = folder_or_scene;
  if (isFile(folder) && endsWithIgnoringCase(folder, ".yaml")) {
    const auto slash = folder.find_last_of('/');
    folder = slash == std::string::npos ? "." : folder.substr(0, slash);
  }
  if (!isDirectory(folder))
    throw InputError(folder + ": no such folder (expected a sequence written by rgbdmap synth)");
  const std::string scene_path = folder + "/scene.yaml";
  if (!isFile(scene_path))
    throw InputError(scene_path + ": missing (is " + folder +
                     " a sequence written by rgbdmap synth?)");
  SyntheticGroundTruth truth;
  truth.scene = SyntheticScene::load(scene_path);
  const std::string surface_path = folder + "/visible_surface.pcd";
  const pcl::PCLPointCloud2 blob = loadCloudBlob(surface_path, "visible surface");
  if (blob.width * blob.height == 0)
    throw InputError(surface_path + ": no points (the reference surface is empty)");
  pcl::fromPCLPointCloud2(blob, truth.visible_surface);
  return truth;
}

}  // namespace rgbdmap
