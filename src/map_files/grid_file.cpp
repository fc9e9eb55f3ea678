#include "rgbdmap/map_files/grid_file.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/map_files/atomic_write.hpp"

namespace rgbdmap {
namespace {

// map_saver's values and thresholds: with negate 0 a pixel's occupancy is (255 - value) / 255.
constexpr unsigned char kOccupiedPixel = 0;
constexpr unsigned char kFreePixel = 254;
constexpr unsigned char kUnknownPixel = 205;
constexpr double kOccupiedThresh = 0.65;
constexpr double kFreeThresh = 0.196;

std::string baseName(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The folder part of a path with its slash ("" for a bare name): what a relative image name joins.
std::string folderPrefixOf(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

std::string pgmBytes(const OccupancyGrid& grid) {
  std::string bytes = fmt::format("P5\n# rgbdmap occupancy grid, {} m cells\n{} {}\n255\n",
                                  grid.resolution, grid.width, grid.height);
  bytes.reserve(bytes.size() + grid.cells.size());
  for (int y = grid.height - 1; y >= 0; --y)
    for (int x = 0; x < grid.width; ++x) {
      const std::int8_t c = grid.at(x, y);
      bytes.push_back(static_cast<char>(c == OccupancyGrid::kOccupied ? kOccupiedPixel
                                        : c == OccupancyGrid::kFree   ? kFreePixel
                                                                      : kUnknownPixel));
    }
  return bytes;
}

std::string yamlText(const OccupancyGrid& grid, const std::string& pgm_path) {
  // The floor's frame in the map's: the grid's corner pose less its offset in the floor.
  const Eigen::Isometry3d map_from_ground =
      grid.map_from_grid *
      Eigen::Translation3d(-grid.origin_in_ground.x(), -grid.origin_in_ground.y(), 0.0);
  const Eigen::Quaterniond q(map_from_ground.linear());
  const Eigen::Vector3d t = map_from_ground.translation();
  return fmt::format(
      "image: {}\n"
      "resolution: {:.6f}\n"
      "origin: [{:.6f}, {:.6f}, 0.0]\n"
      "negate: 0\n"
      "occupied_thresh: {}\n"
      "free_thresh: {}\n"
      "# origin is in the floor's frame: z up, z = 0 on the floor. That frame in the map's (the\n"
      "# PCD's) frame, TUM order (tx ty tz qx qy qz qw):\n"
      "# floor_frame: [{:.6f}, {:.6f}, {:.6f}, {:.9f}, {:.9f}, {:.9f}, {:.9f}]\n",
      baseName(pgm_path), grid.resolution, grid.origin_in_ground.x(), grid.origin_in_ground.y(),
      kOccupiedThresh, kFreeThresh, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
}

}  // namespace

std::string gridYamlPath(const std::string& pgm_path) {
  const std::string suffix = ".pgm";
  if (pgm_path.size() > suffix.size() &&
      pgm_path.compare(pgm_path.size() - suffix.size(), suffix.size(), suffix) == 0)
    return pgm_path.substr(0, pgm_path.size() - suffix.size()) + ".yaml";
  return pgm_path + ".yaml";
}

bool writeGridAtomically(const OccupancyGrid& grid, const std::string& pgm_path,
                         std::string& error) {
  // The image first: a YAML never names an image that is not there.
  return writeBytesAtomically(pgm_path, pgmBytes(grid), error) &&
         writeBytesAtomically(gridYamlPath(pgm_path), yamlText(grid, pgm_path), error);
}

OccupancyGrid readGrid(const std::string& yaml_path) {
  YAML::Node yaml;
  try {
    yaml = YAML::LoadFile(yaml_path);
  } catch (const YAML::Exception& e) {
    throw InputError(yaml_path + ": " + e.what());
  }
  OccupancyGrid grid;
  std::string image;
  double occupied_thresh = 0.0, free_thresh = 0.0;
  int negate = 0;
  try {
    image = yaml["image"].as<std::string>();
    grid.resolution = yaml["resolution"].as<double>();
    const YAML::Node origin = yaml["origin"];
    if (!origin.IsSequence() || origin.size() != 3)
      throw InputError(yaml_path + ": origin must be [x, y, yaw]");
    grid.origin_in_ground = Eigen::Vector2d(origin[0].as<double>(), origin[1].as<double>());
    grid.map_from_grid =
        Eigen::Translation3d(grid.origin_in_ground.x(), grid.origin_in_ground.y(), 0.0) *
        Eigen::AngleAxisd(origin[2].as<double>(), Eigen::Vector3d::UnitZ());
    negate = yaml["negate"].as<int>();
    occupied_thresh = yaml["occupied_thresh"].as<double>();
    free_thresh = yaml["free_thresh"].as<double>();
  } catch (const YAML::Exception& e) {
    throw InputError(yaml_path + ": missing or malformed key (" + e.what() + ")");
  }
  // The floor's frame from our own comment line, where there is one (else the grid lies in the
  // map frame's xy plane, as map_server takes it).
  {
    std::ifstream text(yaml_path);
    std::string line;
    const std::string key = "# floor_frame: [";
    while (std::getline(text, line)) {
      if (line.compare(0, key.size(), key) != 0) continue;
      std::string numbers = line.substr(key.size());
      std::replace(numbers.begin(), numbers.end(), ',', ' ');
      std::replace(numbers.begin(), numbers.end(), ']', ' ');
      std::istringstream in(numbers);
      double v[7];
      for (double& x : v) in >> x;
      if (!in)
        throw InputError(yaml_path + ": floor_frame must hold 7 numbers (tx ty tz qx qy qz qw)");
      Eigen::Isometry3d map_from_ground = Eigen::Isometry3d::Identity();
      map_from_ground.linear() =
          Eigen::Quaterniond(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
      map_from_ground.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
      grid.map_from_grid = map_from_ground * grid.map_from_grid;
    }
  }
  if (!(grid.resolution > 0.0)) throw InputError(yaml_path + ": resolution must be positive");
  const std::string pgm_path =
      image.empty() || image[0] == '/' ? image : folderPrefixOf(yaml_path) + image;
  std::ifstream in(pgm_path, std::ios::binary);
  if (!in)
    throw InputError(pgm_path + ": cannot open the grid's image (named in " + yaml_path + ")");
  std::string magic;
  in >> magic;
  auto skipComments = [&in] {
    in >> std::ws;
    while (in.peek() == '#') {
      std::string line;
      std::getline(in, line);
      in >> std::ws;
    }
  };
  int max_value = 0;
  skipComments();
  in >> grid.width;
  skipComments();
  in >> grid.height;
  skipComments();
  in >> max_value;
  if (magic != "P5" || !in || grid.width <= 0 || grid.height <= 0 || max_value != 255)
    throw InputError(pgm_path + ": not an 8-bit binary PGM (P5, maximum 255)");
  // 2^28 cells is a 800 m square at 5 cm: a larger header is a corrupt file, not a map.
  if (static_cast<double>(grid.width) * grid.height > static_cast<double>(1 << 28))
    throw InputError(pgm_path + ": " + std::to_string(grid.width) + "x" +
                     std::to_string(grid.height) + " cells is more than a grid can hold");
  in.get();  // the one whitespace byte before the pixels
  std::string pixels(static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height),
                     '\0');
  if (!in.read(pixels.data(), static_cast<std::streamsize>(pixels.size())))
    throw InputError(pgm_path + ": truncated: fewer pixels than " + std::to_string(grid.width) +
                     "x" + std::to_string(grid.height));
  grid.cells.assign(pixels.size(), OccupancyGrid::kUnknown);
  for (int row = 0; row < grid.height; ++row)
    for (int x = 0; x < grid.width; ++x) {
      const double value =
          static_cast<unsigned char>(pixels[static_cast<std::size_t>(row) * grid.width + x]);
      const double occupancy = negate ? value / 255.0 : (255.0 - value) / 255.0;
      const std::size_t i = static_cast<std::size_t>(grid.height - 1 - row) * grid.width + x;
      if (occupancy > occupied_thresh)
        grid.cells[i] = OccupancyGrid::kOccupied;
      else if (occupancy < free_thresh)
        grid.cells[i] = OccupancyGrid::kFree;
    }
  return grid;
}

}  // namespace rgbdmap
