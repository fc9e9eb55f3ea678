// A building to test on: the generated office floor (rooms off a corridor, each with a door
// into it), the ground grid that keeps ray casting fast (it must see exactly what testing every
// primitive sees), walls with doors in the scene YAML, and the tour through every room.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <random>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/sim/building.hpp"
#include "rgbdmap/sim/camera_path.hpp"
#include "rgbdmap/sim/synthetic_scene.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using V = Eigen::Vector3d;
using V2 = Eigen::Vector2d;

SyntheticScene building(double length, double width, std::uint64_t seed) {
  BuildingOptions options;
  options.length = length;
  options.width = width;
  options.seed = seed;
  return generateBuilding(options);
}

std::string yamlOf(const SyntheticScene& scene, const std::string& name) {
  const std::string path = test::freshDir() + "/" + name + ".yaml";
  scene.save(path);
  return test::readFile(path);
}

TEST(Building, EveryRoomHasAnOpenDoorFromTheCorridorAndWallsElsewhere) {
  const std::vector<std::pair<double, double>> sizes{{12.0, 8.0}, {30.0, 20.0}, {20.0, 11.0}};
  for (const auto& [length, width] : sizes) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      const SyntheticScene scene = building(length, width, seed);
      const FloorPlan* plan = scene.floorPlan();
      ASSERT_NE(plan, nullptr);
      ASSERT_GE(plan->rooms.size(), 2u);
      const double corridor_y = plan->corridor_from.y();
      bool north = false, south = false;
      for (std::size_t i = 0; i < plan->rooms.size(); ++i) {
        const PlanRoom& room = plan->rooms[i];
        SCOPED_TRACE(room.name + " of " + std::to_string(length) + " x " + std::to_string(width) +
                     ", seed " + std::to_string(seed));
        const double side = room.door.y() > corridor_y ? 1.0 : -1.0;
        (side > 0 ? north : south) = true;
        // Inside the shell, at least 3 m wide and 2.6 m deep, overlapping no other room.
        EXPECT_GE(room.min.x(), -0.5 * length - 1e-9);
        EXPECT_LE(room.max.x(), 0.5 * length + 1e-9);
        EXPECT_GE(room.max.x() - room.min.x(), 2.9);
        EXPECT_GE(room.max.y() - room.min.y(), 2.6);
        for (std::size_t j = 0; j < i; ++j) {
          const PlanRoom& other = plan->rooms[j];
          EXPECT_FALSE(room.min.x() < other.max.x() && other.min.x() < room.max.x() &&
                       room.min.y() < other.max.y() && other.min.y() < room.max.y())
              << "overlaps " << other.name;
        }
        // From the corridor's centre line, through the door at 1 m high, a ray reaches the
        // room's far side (beyond the corridor wall); 0.8 m beside the door, it stops at the wall.
        double t = 0.0;
        V n;
        cv::Vec3b color;
        const V from(room.door.x(), corridor_y, 1.0), towards(0.0, side, 0.0);
        const double far_side = std::abs((side > 0 ? room.max.y() : room.min.y()) - corridor_y);
        const double wall_face = std::abs((side > 0 ? room.min.y() : room.max.y()) - corridor_y);
        ASSERT_TRUE(scene.raycast(from, towards, t, n, color));
        EXPECT_GT(t, wall_face + 0.1);
        EXPECT_LE(t, far_side + 1e-9);
        for (const double beside : {-0.9, 0.9}) {
          const V off(room.door.x() + beside, corridor_y, 1.0);
          if (off.x() <= room.min.x() || off.x() >= room.max.x()) continue;
          ASSERT_TRUE(scene.raycast(off, towards, t, n, color));
          EXPECT_LT(t, wall_face - 0.1) << "beside the door";
        }
        // Above the door, 2.4 m high, the lintel.
        ASSERT_TRUE(scene.raycast(V(room.door.x(), corridor_y, 2.4), towards, t, n, color));
        EXPECT_LT(t, wall_face - 0.1) << "above the door";
        // The way in: every stop is free space with room to look round.
        for (const V2& stop : room.stops)
          EXPECT_TRUE(scene.isFreeSpace(V(stop.x(), stop.y(), plan->camera_height), 0.7));
      }
      EXPECT_TRUE(north && south) << "rooms on both sides of the corridor";
    }
  }
}

TEST(Building, SameSeedSamePlanOtherSeedOtherPlan) {
  const std::string a = yamlOf(building(30, 20, 3), "a");
  EXPECT_EQ(a, yamlOf(building(30, 20, 3), "b"));
  std::set<std::string> plans{a};
  for (std::uint64_t seed = 4; seed <= 7; ++seed) plans.insert(yamlOf(building(30, 20, seed), "c"));
  EXPECT_EQ(plans.size(), 5u);
  // Not only the textures: room counts, widths, doors and furniture move with the seed.
  std::set<std::size_t> primitives;
  std::set<double> doors;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const SyntheticScene scene = building(30, 20, seed);
    primitives.insert(scene.primitives().size());
    doors.insert(scene.floorPlan()->rooms.front().door.x());
  }
  EXPECT_GE(primitives.size(), 3u);
  EXPECT_EQ(doors.size(), 6u);
}

TEST(Building, TooSmallOrBadSizesAreRefusedWithAReason) {
  BuildingOptions options;
  options.length = 12;
  options.width = 6;
  EXPECT_NE(buildingProblem(options).find("does not fit"), std::string::npos);
  EXPECT_THROW(generateBuilding(options), InputError);
  options.width = 8;
  options.height = 1.9;
  EXPECT_NE(buildingProblem(options).find("height"), std::string::npos);
  options.height = 2.8;
  EXPECT_EQ(buildingProblem(options), "");
}

// The grid only decides which primitives to test: every ray and every distance must come out
// exactly as testing them all, from anywhere in the building, in any direction.
TEST(Building, GridSeesExactlyWhatTestingEveryPrimitiveSees) {
  const SyntheticScene scene = building(30, 20, 2);
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> x(-15.5, 15.5), y(-10.5, 10.5), z(-0.2, 3.0),
      unit(-1.0, 1.0);
  int hits = 0;
  for (int k = 0; k < 20000; ++k) {
    const V origin(x(random), y(random), z(random));
    V direction(unit(random), unit(random), 0.3 * unit(random));
    if (k % 10 == 0) direction = V(0, 0, unit(random) > 0 ? 1 : -1);  // straight up or down
    if (k % 10 == 1) direction.y() = 0.0;                             // along a grid axis
    double t1 = 0, t2 = 0;
    V n1, n2;
    cv::Vec3b c1, c2;
    const bool h1 = scene.raycast(origin, direction, t1, n1, c1);
    const bool h2 = scene.raycastEveryPrimitive(origin, direction, t2, n2, c2);
    ASSERT_EQ(h1, h2) << k;
    if (h1) {
      ++hits;
      ASSERT_EQ(t1, t2) << k;
      ASSERT_EQ(n1, n2) << k;
      ASSERT_EQ(c1, c2) << k;
    }
    ASSERT_EQ(scene.distance(origin), scene.distanceEveryPrimitive(origin)) << k;
  }
  EXPECT_GT(hits, 15000);
}

TEST(SceneWalls, AWallWithADoorSeenThroughTheDoorBesideItAndAboveIt) {
  const std::string dir = test::freshDir();
  const std::string path = dir + "/walls.yaml";
  std::ofstream(path)
      << "primitives:\n"
         "  - kind: room\n    min: [-3, -2, 0]\n    max: [3, 2, 2.8]\n"
         "    texture: {pattern: checker, color_a: [200, 190, 170], color_b: [90, 70, 60], "
         "scale: 0.25}\n"
         "  - kind: wall\n    name: middle\n    from: [0, -2]\n    to: [0, 2]\n"
         "    height: 2.8\n    thickness: 0.1\n"
         "    doors: [{at: 2.0, width: 1.0, height: 2.1}]\n"
         "    texture: {pattern: stripes, color_a: [240, 240, 240], color_b: [40, 40, 90], "
         "scale: 0.1}\n";
  const SyntheticScene scene = SyntheticScene::load(path);
  ASSERT_EQ(scene.walls().size(), 1u);
  EXPECT_EQ(scene.primitives().size(), 4u);  // the room, two sides of the door and the lintel
  double t = 0.0;
  V n;
  cv::Vec3b color;
  // Through the door (y = 0, 1 m high): the far wall x = 3, 5 m away.
  ASSERT_TRUE(scene.raycast(V(-2, 0, 1.0), V(1, 0, 0), t, n, color));
  EXPECT_NEAR(t, 5.0, 1e-12);
  // Beside it (y = 0.7): the wall's face x = -0.05.
  ASSERT_TRUE(scene.raycast(V(-2, 0.7, 1.0), V(1, 0, 0), t, n, color));
  EXPECT_NEAR(t, 1.95, 1e-12);
  EXPECT_TRUE(n.isApprox(V(-1, 0, 0)));
  // Above it (2.5 m): the lintel; from the other side, its other face.
  ASSERT_TRUE(scene.raycast(V(-2, 0, 2.5), V(1, 0, 0), t, n, color));
  EXPECT_NEAR(t, 1.95, 1e-12);
  ASSERT_TRUE(scene.raycast(V(2, 0, 2.5), V(-1, 0, 0), t, n, color));
  EXPECT_NEAR(t, 1.95, 1e-12);
  // The door's jamb (y = 0.5) seen along the wall, and the lintel's underside from below.
  ASSERT_TRUE(scene.raycast(V(0, -0.2, 1.0), V(0, 1, 0), t, n, color));
  EXPECT_NEAR(t, 0.7, 1e-12);
  ASSERT_TRUE(scene.raycast(V(0, 0, 1.0), V(0, 0, 1), t, n, color));
  EXPECT_NEAR(t, 1.1, 1e-12);
  // Distances: beside the wall's face, and in the doorway to its jambs.
  EXPECT_NEAR(scene.distance(V(-0.35, 1.0, 1.4)), 0.3, 1e-12);
  EXPECT_NEAR(scene.distance(V(0, 0, 1.4)), 0.5, 1e-12);
  EXPECT_TRUE(scene.isFreeSpace(V(0, 0, 1.4), 0.45));
  EXPECT_FALSE(scene.isFreeSpace(V(0, 1.0, 1.4), 0.0));  // inside the wall

  // Written and read back: the same wall (not three boxes), the same rays.
  scene.save(dir + "/again.yaml");
  EXPECT_NE(test::readFile(dir + "/again.yaml").find("kind: wall"), std::string::npos);
  const SyntheticScene again = SyntheticScene::load(dir + "/again.yaml");
  ASSERT_EQ(again.walls().size(), 1u);
  ASSERT_EQ(again.primitives().size(), scene.primitives().size());
  for (std::size_t k = 0; k < scene.primitives().size(); ++k) {
    EXPECT_EQ(again.primitives()[k].min, scene.primitives()[k].min);
    EXPECT_EQ(again.primitives()[k].max, scene.primitives()[k].max);
  }
  // A generated building read back from its YAML: same primitives in the same order, same plan.
  const SyntheticScene floor = building(20, 11, 5);
  floor.save(dir + "/floor.yaml");
  const SyntheticScene read = SyntheticScene::load(dir + "/floor.yaml");
  ASSERT_EQ(read.primitives().size(), floor.primitives().size());
  for (std::size_t k = 0; k < floor.primitives().size(); ++k) {
    EXPECT_EQ(read.primitives()[k].min, floor.primitives()[k].min) << k;
    EXPECT_EQ(read.primitives()[k].max, floor.primitives()[k].max) << k;
    EXPECT_EQ(read.primitives()[k].center, floor.primitives()[k].center) << k;
  }
  ASSERT_NE(read.floorPlan(), nullptr);
  ASSERT_EQ(read.floorPlan()->rooms.size(), floor.floorPlan()->rooms.size());
  EXPECT_EQ(read.floorPlan()->rooms.back().stops, floor.floorPlan()->rooms.back().stops);
  EXPECT_EQ(yamlOf(read, "read"), yamlOf(floor, "floor"));
}

TEST(SceneWalls, BadWallsNameFileLineAndProblem) {
  const std::string dir = test::freshDir();
  const std::string path = dir + "/bad.yaml";
  const std::string room =
      "primitives:\n"
      "  - kind: room\n    min: [-3, -2, 0]\n    max: [3, 2, 2.8]\n"
      "    texture: {pattern: checker, color_a: [1, 2, 3], color_b: [4, 5, 6], scale: 0.2}\n";
  const std::string texture =
      "    texture: {pattern: checker, color_a: [1, 2, 3], color_b: [4, 5, 6], scale: 0.2}\n";
  const std::pair<std::string, std::string> cases[] = {
      {"    from: [0, -2]\n    to: [1, 2]\n    height: 2.8\n    thickness: 0.1\n",
       "neither along x nor along y"},
      {"    from: [0, -2]\n    to: [0, 2]\n    height: 2.8\n    thickness: 0.1\n"
       "    doors: [{at: 3.8, width: 1.0, height: 2.1}]\n",
       "outside the 4.000 m wall"},
      {"    from: [0, -2]\n    to: [0, 2]\n    height: 2.8\n    thickness: 0.1\n"
       "    doors: [{at: 1.0, width: 1.0, height: 2.1}, {at: 1.5, width: 1.0, height: 2.1}]\n",
       "overlap"},
      {"    from: [0, -2]\n    to: [0, 2]\n    height: 2.8\n    thickness: 0\n", "thickness"},
      {"    from: [0, -2, 0]\n    to: [0, 2]\n    height: 2.8\n    thickness: 0.1\n",
       "list of 2 numbers"},
  };
  for (const auto& [wall, problem] : cases) {
    std::ofstream(path) << room << "  - kind: wall\n    name: w\n" << wall << texture;
    try {
      SyntheticScene::load(path);
      ADD_FAILURE() << "expected an InputError for " << wall;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path + ":"), std::string::npos) << message;
      EXPECT_NE(message.find(problem), std::string::npos) << message;
    }
  }
  // A tour needs a floor plan.
  SyntheticSequenceOptions options;
  options.path = "tour";
  EXPECT_THROW(makeCameraPath(SyntheticScene::defaultRoom(), options, 10.0), InputError);
}

// The tour of a floor, sampled as a camera would be (30 Hz): never nearer than the depth
// sensor's range (0.5 m) to any surface, into every room, back where it began, and smooth.
void checkTour(const SyntheticScene& scene, std::uint64_t seed) {
  const FloorPlan& plan = *scene.floorPlan();
  SyntheticSequenceOptions options;
  const TourPath tour(plan, seed, options.tour_speed, options.tour_turn_rate);
  const double fps = 30.0;
  const int frames = static_cast<int>(std::floor(tour.duration() * fps)) + 1;
  std::vector<bool> visited(plan.rooms.size(), false);
  double nearest = 1e9, longest_step = 0.0, fastest_turn = 0.0, walked = 0.0;
  Eigen::Isometry3d previous = tour.pose(0.0);
  for (int i = 0; i < frames; ++i) {
    const Eigen::Isometry3d pose = tour.pose(i / fps);
    const V p = pose.translation();
    ASSERT_TRUE(scene.isFreeSpace(p, 0.0)) << "frame " << i << " at " << p.transpose();
    nearest = std::min(nearest, scene.distance(p));
    for (std::size_t r = 0; r < plan.rooms.size(); ++r) {
      const PlanRoom& room = plan.rooms[r];
      if (p.x() > room.min.x() && p.x() < room.max.x() && p.y() > room.min.y() &&
          p.y() < room.max.y())
        visited[r] = true;
    }
    const double step = (p - previous.translation()).norm();
    walked += step;
    longest_step = std::max(longest_step, step);
    fastest_turn = std::max(
        fastest_turn, Eigen::AngleAxisd(previous.linear().transpose() * pose.linear()).angle());
    // Upright: the camera's x axis stays level within the roll's few degrees.
    ASSERT_LT(std::abs(pose.linear().col(0).z()), 0.1) << "frame " << i;
    previous = pose;
  }
  EXPECT_GE(nearest, 0.5);
  for (std::size_t r = 0; r < plan.rooms.size(); ++r)
    EXPECT_TRUE(visited[r]) << plan.rooms[r].name << " never entered";
  // A step of at most 0.5 m/s plus the sway (3 cm at up to 7 rad/s per axis): under 3 cm a frame;
  // a turn of at most 0.5 rad/s plus the sway's look: under 2 degrees a frame.
  EXPECT_LT(longest_step, 0.03);
  EXPECT_LT(fastest_turn, 2.0 * M_PI / 180.0);
  EXPECT_GT(walked, tour.length());
  // Back where it began, facing the same way, up to the hand's sway.
  const Eigen::Isometry3d back = tour.pose(0.0).inverse() * tour.pose(tour.duration());
  EXPECT_LT(back.translation().norm(), 0.2);
  EXPECT_LT(Eigen::AngleAxisd(back.linear()).angle(), 0.6);
  std::cout << plan.rooms.size() << " rooms: " << tour.length() << " m in " << tour.duration()
            << " s, nearest surface " << nearest << " m, longest step " << longest_step
            << " m, fastest turn " << fastest_turn * 180.0 / M_PI << " deg a frame\n";
}

TEST(TourPath, VisitsEveryRoomKeepsClearAndEndsWhereItBegan) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("12 x 8, seed " + std::to_string(seed));
    checkTour(building(12, 8, seed), seed);
  }
  SCOPED_TRACE("30 x 20");
  checkTour(building(30, 20, 1), 1);
}

TEST(TourPath, AFloorPlanFromYamlIsToured) {
  // A plan of one's own: one room north of a short corridor, its door at x = 0.
  const std::string dir = test::freshDir();
  const std::string path = dir + "/plan.yaml";
  std::ofstream(path)
      << "primitives:\n"
         "  - kind: room\n    min: [-3, -1.5, 0]\n    max: [3, 4.5, 2.8]\n"
         "    texture: {pattern: checker, color_a: [200, 190, 170], color_b: [90, 70, 60], "
         "scale: 0.25}\n"
         "  - kind: wall\n    from: [-3, 0.5]\n    to: [3, 0.5]\n    height: 2.8\n"
         "    thickness: 0.1\n    doors: [{at: 3.0, width: 1.2, height: 2.1}]\n"
         "    texture: {pattern: stripes, color_a: [240, 240, 240], color_b: [40, 40, 90], "
         "scale: 0.1}\n"
         "floor_plan:\n"
         "  corridor: {from: [-2, -0.5], to: [2, -0.5]}\n"
         "  camera_height: 1.4\n"
         "  rooms:\n"
         "    - {name: lab, min: [-3, 0.55], max: [3, 4.5], door: [0, 0.5], stops: [[0, 2.5]]}\n";
  const SyntheticScene scene = SyntheticScene::load(path);
  ASSERT_NE(scene.floorPlan(), nullptr);
  checkTour(scene, 1);
}

}  // namespace
}  // namespace rgbdmap
