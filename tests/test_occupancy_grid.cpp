// Maps a robot can drive in (issue 29): which way is up, where the floor is, and the occupancy
// grid written with every save in map_server's format, against the exact geometry of a synthetic
// room and the accelerometer of a real Kinect recording.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/accelerometer_log.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/map_files/grid_file.hpp"
#include "rgbdmap/mapping/floor_finder.hpp"
#include "rgbdmap/mapping/ground_frame.hpp"
#include "rgbdmap/mapping/occupancy_grid.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

constexpr double kOneDegree = M_PI / 180.0;

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
}

// Surface points on a rectangle of the plane z = f(x, y) = a x + b y + c, spaced `step`.
void addPatch(MapCloud& cloud, double x0, double x1, double y0, double y1, double a, double b,
              double c, double step = 0.02) {
  for (double x = x0; x <= x1; x += step)
    for (double y = y0; y <= y1; y += step) {
      pcl::PointXYZRGB p;
      p.x = static_cast<float>(x);
      p.y = static_cast<float>(y);
      p.z = static_cast<float>(a * x + b * y + c);
      cloud.push_back(p);
    }
}

// A wall x = const from floor to 2.5 m.
void addWall(MapCloud& cloud, double x, double y0, double y1, double step = 0.02) {
  for (double y = y0; y <= y1; y += step)
    for (double z = 0.0; z <= 2.5; z += step) {
      pcl::PointXYZRGB p;
      p.x = static_cast<float>(x);
      p.y = static_cast<float>(y);
      p.z = static_cast<float>(z);
      cloud.push_back(p);
    }
}

TEST(FloorFinder, FindsTheTiltedFloorUnderATableFromAPoorGuessOfUp) {
  // A floor tilted 2 degrees about y, a large table top 0.75 m above it and a wall; cameras at
  // 1.5 m. The guess of up is 30 degrees off (a camera looking down at the table).
  const double slope = std::tan(2.0 * kOneDegree);
  MapCloud map;
  addPatch(map, -2.0, 2.0, -2.0, 2.0, slope, 0.0, 0.0);   // floor: 40k points
  addPatch(map, -0.5, 1.0, -0.5, 0.5, slope, 0.0, 0.75);  // table top: 3.8k points
  addWall(map, 2.0, -2.0, 2.0);
  const Eigen::Vector3d guess =
      Eigen::AngleAxisd(30.0 * kOneDegree, Eigen::Vector3d::UnitX()) * Eigen::Vector3d::UnitZ();
  const std::optional<FloorPlane> floor =
      FloorFinder{}.find(map, guess, {Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(1, 0, 1.6)});
  ASSERT_TRUE(floor.has_value());
  const Eigen::Vector3d truth = Eigen::Vector3d(-slope, 0.0, 1.0).normalized();
  EXPECT_LT(angleBetween(floor->up, truth), 0.1 * kOneDegree);
  EXPECT_NEAR(floor->heightOf(Eigen::Vector3d(0, 0, 0)), 0.0, 0.005);
  EXPECT_GT(floor->support, 30000u);
}

TEST(FloorFinder, FindsNothingWithoutLevelSurfacesBelowTheCameras) {
  MapCloud map;
  addWall(map, 2.0, -2.0, 2.0);
  addPatch(map, -1.0, 1.0, -1.0, 1.0, 0.0, 0.0, 2.0);  // a ceiling above the cameras
  EXPECT_FALSE(FloorFinder{}.find(map, Eigen::Vector3d::UnitZ(), {Eigen::Vector3d(0, 0, 1.5)}));
}

TEST(GroundFrame, ConfiguredUpAndFloorWinAndBadValuesAreRefused) {
  MapCloud map;
  addPatch(map, -2.0, 2.0, -2.0, 2.0, 0.0, 0.0, 0.0);
  UpEvidence evidence;
  evidence.camera_up = Eigen::Vector3d(0, 0, 3);
  evidence.cameras = {Eigen::Vector3d(0, 0, 1.5)};
  UpOptions options;
  GroundFrame found = GroundFrame::resolve(map, evidence, options);
  EXPECT_EQ(found.up_source, GroundFrame::UpSource::kFloor);
  EXPECT_EQ(found.floor_source, GroundFrame::FloorSource::kPlane);
  EXPECT_LT(angleBetween(found.up(), Eigen::Vector3d::UnitZ()), 1e-6);
  EXPECT_NEAR(found.map_from_ground.translation().z(), 0.0, 1e-6);
  EXPECT_NE(found.describe().find("up from the floor plane"), std::string::npos)
      << found.describe();

  options.vector = "0,0.1,1";
  options.floor_height = "-0.25";
  const GroundFrame configured = GroundFrame::resolve(map, evidence, options);
  EXPECT_EQ(configured.up_source, GroundFrame::UpSource::kConfigured);
  EXPECT_EQ(configured.floor_source, GroundFrame::FloorSource::kConfigured);
  EXPECT_LT(angleBetween(configured.up(), Eigen::Vector3d(0, 0.1, 1)), 1e-9);
  EXPECT_NEAR(configured.up().dot(configured.map_from_ground.translation()), -0.25, 1e-9);

  options.vector = "0,0";
  EXPECT_THROW(GroundFrame::resolve(map, evidence, options), std::invalid_argument);
  options.vector = "auto";
  options.floor_height = "low";
  EXPECT_THROW(GroundFrame::resolve(map, evidence, options), std::invalid_argument);
}

TEST(GridFile, WritesWhatMapServerReadsBack) {
  MapCloud map;
  addPatch(map, 0.0, 2.0, 0.0, 1.0, 0.0, 0.0, 0.0);
  addWall(map, 1.0, 0.0, 1.0);
  GroundFrame ground;
  ground.map_from_ground = Eigen::Translation3d(0.3, -0.2, 0.1) *
                           Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 1, 0).normalized());
  // The map expressed in that ground frame, so the grid has the same cells whatever the frame.
  MapCloud moved;
  for (const auto& p : map.points) {
    pcl::PointXYZRGB q = p;
    q.getVector3fMap() = (ground.map_from_ground * p.getVector3fMap().cast<double>()).cast<float>();
    moved.push_back(q);
  }
  const OccupancyGrid grid = OccupancyGrid::build(moved, ground, GridOptions{});
  ASSERT_GT(grid.count(OccupancyGrid::kOccupied), 0u);
  ASSERT_GT(grid.count(OccupancyGrid::kFree), 0u);
  ASSERT_GT(grid.count(OccupancyGrid::kUnknown), 0u);  // the margin

  const std::string dir = test::freshDir();
  std::string error;
  ASSERT_TRUE(writeGridAtomically(grid, dir + "/g.pgm", error)) << error;
  const OccupancyGrid back = readGrid(dir + "/g.yaml");
  EXPECT_EQ(back.width, grid.width);
  EXPECT_EQ(back.height, grid.height);
  EXPECT_DOUBLE_EQ(back.resolution, grid.resolution);
  EXPECT_EQ(back.cells, grid.cells);
  EXPECT_TRUE(back.map_from_grid.isApprox(grid.map_from_grid, 1e-6));
  // The wall at x = 1 occupies the cells whose centres are within a cell of it, in the map frame.
  for (int y = 0; y < grid.height; ++y)
    for (int x = 0; x < grid.width; ++x) {
      if (grid.at(x, y) != OccupancyGrid::kOccupied) continue;
      const Eigen::Vector3d centre =
          ground.map_from_ground.inverse() * grid.map_from_grid *
          Eigen::Vector3d((x + 0.5) * grid.resolution, (y + 0.5) * grid.resolution, 0.0);
      EXPECT_NEAR(centre.x(), 1.0, grid.resolution);
    }
  const cv::Mat image = cv::imread(dir + "/g.pgm", cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, grid.width);
  EXPECT_EQ(image.rows, grid.height);
  EXPECT_EQ(image.type(), CV_8UC1);

  // A YAML that names no image, and an image cut short, are refused naming the file.
  std::ofstream(dir + "/bad.yaml") << "image: missing.pgm\nresolution: 0.05\n";
  try {
    readGrid(dir + "/bad.yaml");
    ADD_FAILURE() << "a YAML without origin was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
  }
  const std::string pgm = test::readFile(dir + "/g.pgm");
  std::ofstream(dir + "/g.pgm", std::ios::binary) << pgm.substr(0, pgm.size() / 2);
  try {
    readGrid(dir + "/g.yaml");
    ADD_FAILURE() << "a truncated PGM was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("g.pgm: truncated"), std::string::npos) << e.what();
  }
}

// Cells (x, y) of the grid, as one integer key.
std::int64_t cellKey(int x, int y) { return static_cast<std::int64_t>(y) * 1000000 + x; }

bool nearAny(const std::set<std::int64_t>& cells, int x, int y, int radius) {
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx)
      if (cells.count(cellKey(x + dx, y + dy))) return true;
  return false;
}

// The angle between the final map's floor and the accelerometer's up, from a run's --stats.
double degreesFromTheAccelerometer(const std::string& stats_path) {
  const std::string stats = test::readFile(stats_path);
  const std::size_t ground = stats.find("\"ground\": \"");
  const std::size_t at = stats.find(" degrees from the accelerometer", ground);
  if (ground == std::string::npos || at == std::string::npos) {
    ADD_FAILURE() << stats_path << " says no angle to the accelerometer:\n" << stats;
    return 180.0;
  }
  const std::size_t start = stats.rfind(", ", at) + 2;
  return std::stod(stats.substr(start, at - start));
}

TEST(OccupancyGrid, DrawsTheSyntheticRoomsFloorPlan) {
  const std::string room =
      test::sharedSynthetic("room_6x5x3_90_frames", " --room 6x5x3 --fps 10 --frames 90");
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + room + " --out " + dir +
                          "/map.pcd --grid " + dir +
                          "/floor.pgm --rate max --set keyframe.every_n=1 --set "
                          "filter.max_depth=5 -q --no-render --stats " +
                          dir + "/stats.json",
                      &output),
            0)
      << output;
  EXPECT_NE(output.find("grid: up from the floor plane"), std::string::npos) << output;
  // The synthetic accelerometer (the path's acceleration and gravity) agrees with the floor of the
  // final map. Measured: 0.2 degrees (release and ASan, 91,921 floor points). Within a degree: the
  // path's acceleration tilts the accelerometer's mean by a few tenths. (The log says it when its
  // sources change: a slow run's says it for a checkpoint of part of the floor, 1.1 degrees on
  // 48,519 points under ASan with the cores busy.)
  const double degrees = degreesFromTheAccelerometer(dir + "/stats.json");
  EXPECT_LT(degrees, 1.0);
  const OccupancyGrid grid = readGrid(dir + "/floor.yaml");  // map_server's rules
  ASSERT_GT(grid.width, 0);
  const cv::Mat image = cv::imread(dir + "/floor.pgm", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(image.cols, grid.width);
  ASSERT_EQ(image.rows, grid.height);

  // The grid in the scene's frame (the trajectory aligned to the ground truth: the identity with
  // the ground truth's poses): the floor is z = 0, up is +z.
  const Eigen::Isometry3d scene_from_map =
      absoluteTrajectoryError(Trajectory::load(dir + "/map_keyframes.txt"),
                              Trajectory::load(room + "/groundtruth.txt"))
          .alignment;
  const Eigen::Isometry3d scene_from_grid = scene_from_map * grid.map_from_grid;
  const Eigen::Vector3d up = scene_from_grid.linear().col(2);
  EXPECT_LT(angleBetween(up, Eigen::Vector3d::UnitZ()), 1.0 * kOneDegree);
  EXPECT_NEAR(scene_from_grid.translation().z(), 0.0, 0.02);

  // The truth: the cells of the surfaces the camera saw, in the height band (occupied) and on the
  // floor (seen floor).
  const GridOptions options;
  const SyntheticGroundTruth truth = loadSyntheticGroundTruth(room);
  const Eigen::Isometry3d grid_from_scene = scene_from_grid.inverse();
  std::set<std::int64_t> occupied, floor;
  for (const auto& p : truth.visible_surface.points) {
    const Eigen::Vector3d q = grid_from_scene * p.getVector3fMap().cast<double>();
    const int x = static_cast<int>(std::floor(q.x() / grid.resolution));
    const int y = static_cast<int>(std::floor(q.y() / grid.resolution));
    if (p.z >= options.min_height && p.z <= options.max_height) occupied.insert(cellKey(x, y));
    if (std::abs(p.z) < 0.01) floor.insert(cellKey(x, y));
  }
  ASSERT_GT(occupied.size(), 100u);
  std::set<std::int64_t> found;
  for (int y = 0; y < grid.height; ++y)
    for (int x = 0; x < grid.width; ++x)
      if (grid.at(x, y) == OccupancyGrid::kOccupied) found.insert(cellKey(x, y));
  std::size_t true_positives = 0, covered = 0, free_on_floor = 0, seen_floor = 0, occupied_free = 0;
  for (const std::int64_t c : found)
    true_positives +=
        nearAny(occupied, static_cast<int>(c % 1000000), static_cast<int>(c / 1000000), 1);
  for (const std::int64_t c : occupied) {
    const int x = static_cast<int>(c % 1000000), y = static_cast<int>(c / 1000000);
    covered += nearAny(found, x, y, 1);
    if (x >= 0 && y >= 0 && x < grid.width && y < grid.height &&
        grid.at(x, y) == OccupancyGrid::kFree)
      ++occupied_free;
  }
  for (const std::int64_t c : floor) {
    const int x = static_cast<int>(c % 1000000), y = static_cast<int>(c / 1000000);
    if (nearAny(occupied, x, y, 2) || x < 0 || y < 0 || x >= grid.width || y >= grid.height)
      continue;  // next to an obstacle: a cell's width of floor may be hidden by it
    ++seen_floor;
    free_on_floor += grid.at(x, y) == OccupancyGrid::kFree;
  }
  const double precision = static_cast<double>(true_positives) / found.size();
  const double recall = static_cast<double>(covered) / occupied.size();
  const double f = 2.0 * precision * recall / (precision + recall);
  const double free_recall = static_cast<double>(free_on_floor) / seen_floor;
  const double occupied_marked_free = static_cast<double>(occupied_free) / occupied.size();
  std::cout << "grid " << grid.width << "x" << grid.height << ": occupied precision " << precision
            << " recall " << recall << " F " << f << "; free recall on seen floor " << free_recall
            << " (" << seen_floor << " cells); occupied marked free " << occupied_marked_free
            << "\n";
  ::testing::Test::RecordProperty("grid_f_score", std::to_string(f));
  EXPECT_GE(f, 0.9);
  EXPECT_GE(free_recall, 0.95);
  EXPECT_LE(occupied_marked_free, 0.01);
}

// TUM's Kinect accelerometer against the motion-capture ground truth, whose z is up: the axes
// upInCamera() assumes put the accelerometer's up within a few degrees of it on every excerpt.
TEST(AccelerometerLog, GivesUpInTheCameraFrameOfTheRealKinect) {
  for (const std::string& name : {test::kXyz, test::kRpy}) {
    const std::string folder = test::tumDir(name);
    const AccelerometerLog log = AccelerometerLog::load(folder + "/accelerometer.txt");
    const Trajectory truth = Trajectory::load(folder + "/groundtruth.txt");
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int samples = 0;
    for (const StampedPose& p : truth.poses()) {
      const std::optional<Eigen::Vector3d> up = log.upAt(p.timestamp);
      if (!up) continue;
      sum += p.pose.linear() * *up;
      ++samples;
    }
    ASSERT_GT(samples, 50) << name;
    const double angle = angleBetween(sum, Eigen::Vector3d::UnitZ());
    std::cout << name << ": accelerometer up " << angle / kOneDegree
              << " degrees from the motion capture's z over " << samples << " poses\n";
    EXPECT_LT(angle, 5.0 * kOneDegree) << name;
  }
}

TEST(AccelerometerLog, RefusesABadLineNamingIt) {
  const std::string dir = test::freshDir();
  std::ofstream(dir + "/accelerometer.txt") << "# accelerometer data\n1.0 0 9.8 0\n2.0 0 9.8\n";
  try {
    AccelerometerLog::load(dir + "/accelerometer.txt");
    ADD_FAILURE() << "a line of 3 fields was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("accelerometer.txt:3"), std::string::npos) << e.what();
  }
}

// A real recording with an accelerometer: the floor (or the desk standing in for it) found in the
// map agrees with the accelerometer's up, and the log says which was used.
TEST(GroundFrame, FloorOfARealMapAgreesWithTheAccelerometer) {
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(
      test::run(test::binary() + " --source tum:" + test::tumDir(test::kRpy) + " --out " + dir +
                    "/map.pcd --grid " + dir +
                    "/grid.pgm --rate max --set pose.source=odometry -q --no-render --stats " +
                    dir + "/stats.json",
                &output),
      0)
      << output;
  const double degrees = degreesFromTheAccelerometer(dir + "/stats.json");
  std::cout << "floor plane " << degrees << " degrees from the accelerometer's up\n";
  // The ground-truth poses' map gives 2.1 degrees; odometry maps 2.1-3.3 with the same rotation
  // error of their poses (2.3 degrees on average from the motion capture's), depending on which
  // horizontal surface the finder takes (the desk or the floor, 12 cm apart). The accelerometer
  // itself agrees with the motion capture within 5 (AccelerometerLog's test).
  EXPECT_LT(degrees, 4.0);
  const OccupancyGrid grid = readGrid(dir + "/grid.yaml");
  EXPECT_GT(grid.count(OccupancyGrid::kFree), 100u);
  EXPECT_GT(grid.count(OccupancyGrid::kOccupied), 10u);
}

}  // namespace
}  // namespace rgbdmap
