#include "rgbdmap/sim/building.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {
namespace {

using V2 = Eigen::Vector2d;
using V3 = Eigen::Vector3d;

constexpr double kCorridorWall = 0.15;  // m thick
constexpr double kPartition = 0.10;
constexpr double kMinRoomWidth = 3.0;  // m: a door with wall either side, a stop, furniture
constexpr double kMinRoomDepth = 2.6;  // m: a door, a stop 1.3 m in, furniture beyond it
constexpr double kMinCorridor = 2.0;   // m clear: 1 m either side of a camera in its middle
constexpr double kDoorHeight = 2.1;
constexpr double kEndClearance = 1.2;    // m from the corridor's end walls to where a tour turns
constexpr double kJambClearance = 0.35;  // m of wall at least between a door and a partition
constexpr double kStopSpacing = 4.5;     // m: a deeper room gets more stops (the sensor's range)
// m on the ground between furniture and the way from a door to the stops (a camera passes at
// 0.5 m from everything, with a hand's sway of a few centimetres).
constexpr double kWayClearance = 0.75;

// Uniform in [0, 1) from the generator's raw bits: the same plan from a seed whatever the
// standard library (its distributions are not specified bit for bit).
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed ^ 0xB01D1A9ull) {}
  double unit() { return static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int index(int n) { return std::min(n - 1, static_cast<int>(unit() * n)); }

 private:
  std::mt19937_64 engine_;
};

SurfaceTexture makeTexture(SurfaceTexture::Pattern pattern, cv::Vec3b a, cv::Vec3b b, double scale,
                           double angle = 0.0) {
  SurfaceTexture t;
  t.pattern = pattern;
  t.color_a = a;
  t.color_b = b;
  t.scale = scale;
  t.angle_deg = angle;
  return t;
}

// A light and a dark colour of one random hue family, far enough apart for image gradients.
SurfaceTexture randomTexture(Random& random, double min_scale, double max_scale) {
  auto colour = [&](double lo, double hi) {
    cv::Vec3b c;
    for (int k = 0; k < 3; ++k) c[k] = static_cast<unsigned char>(random.uniform(lo, hi));
    return c;
  };
  const SurfaceTexture::Pattern patterns[3] = {SurfaceTexture::Pattern::kChecker,
                                               SurfaceTexture::Pattern::kStripes,
                                               SurfaceTexture::Pattern::kWaves};
  const SurfaceTexture::Pattern pattern = patterns[random.index(3)];
  const cv::Vec3b light = colour(150, 245), dark = colour(25, 110);
  return makeTexture(pattern, light, dark, random.uniform(min_scale, max_scale),
                     random.uniform(-60.0, 60.0));
}

// Ground distance between an axis-aligned rectangle and a segment along y at x (y from y0 to y1).
double rectangleToSegment(const V2& lo, const V2& hi, double x, double y0, double y1) {
  const double dx = std::max({0.0, lo.x() - x, x - hi.x()});
  const double dy = std::max({0.0, lo.y() - std::max(y0, y1), std::min(y0, y1) - hi.y()});
  return std::hypot(dx, dy);
}

double rectangleToPoint(const V2& lo, const V2& hi, const V2& p) {
  return rectangleToSegment(lo, hi, p.x(), p.y(), p.y());
}

bool overlap(const V2& lo_a, const V2& hi_a, const V2& lo_b, const V2& hi_b, double gap) {
  return lo_a.x() < hi_b.x() + gap && lo_b.x() < hi_a.x() + gap && lo_a.y() < hi_b.y() + gap &&
         lo_b.y() < hi_a.y() + gap;
}

// Desks, cabinets, crates and balls along the walls of `room`, away from the way in.
void furnish(SyntheticScene& scene, const PlanRoom& room, double height, Random& random) {
  const V2 size = room.max - room.min;
  const int wanted = std::clamp(static_cast<int>(std::lround(size.x() * size.y() / 7.0)), 2, 8);
  const double way_end = room.stops.back().y();
  struct Placed {
    V2 lo, hi;
  };
  std::vector<Placed> placed;
  int desks = 0, cabinets = 0, crates = 0, balls = 0;
  for (int attempt = 0; attempt < 80 && static_cast<int>(placed.size()) < wanted; ++attempt) {
    const int type = random.index(10);  // 0-3 desk, 4-6 cabinet, 7-8 crate, 9 ball
    double along = 0.0, across = 0.0, top = 0.0;
    if (type <= 3) {
      along = random.uniform(1.2, 1.8);
      across = random.uniform(0.6, 0.8);
      top = random.uniform(0.72, 0.76);
    } else if (type <= 6) {
      along = random.uniform(0.8, 1.2);
      across = random.uniform(0.4, 0.5);
      top = std::min(random.uniform(1.0, 2.0), height - 0.4);
    } else if (type <= 8) {
      along = across = random.uniform(0.4, 0.6);
      top = along;
    } else {
      along = across = 2.0 * random.uniform(0.15, 0.3);  // a ball's footprint
      top = along;
    }
    // Against one of the four walls, 3 cm off it, anywhere along it.
    const int wall = random.index(4);
    const bool along_x = wall < 2;
    const V2 extent = along_x ? V2(along, across) : V2(across, along);
    if (extent.x() > size.x() - 0.1 || extent.y() > size.y() - 0.1) continue;
    V2 lo;
    if (along_x) {
      lo.x() = random.uniform(room.min.x() + 0.03, room.max.x() - 0.03 - extent.x());
      lo.y() = wall == 0 ? room.min.y() + 0.03 : room.max.y() - 0.03 - extent.y();
    } else {
      lo.y() = random.uniform(room.min.y() + 0.03, room.max.y() - 0.03 - extent.y());
      lo.x() = wall == 2 ? room.min.x() + 0.03 : room.max.x() - 0.03 - extent.x();
    }
    const V2 hi = lo + extent;
    if (rectangleToSegment(lo, hi, room.door.x(), room.door.y(), way_end) < kWayClearance) continue;
    bool clear = true;
    for (const V2& stop : room.stops) clear &= rectangleToPoint(lo, hi, stop) >= kWayClearance;
    for (const Placed& other : placed) clear &= !overlap(lo, hi, other.lo, other.hi, 0.1);
    if (!clear) continue;
    const std::string prefix = room.name + " ";
    if (type <= 3) {
      scene.addBox(V3(lo.x(), lo.y(), 0.0), V3(hi.x(), hi.y(), top),
                   makeTexture(SurfaceTexture::Pattern::kStripes, {150, 95, 45}, {235, 190, 120},
                               random.uniform(0.04, 0.08), random.uniform(-40.0, 40.0)),
                   prefix + "desk " + std::to_string(++desks));
      // Something on most desks: a box file or a ball.
      if (random.unit() < 0.7) {
        const V2 c = 0.5 * (lo + hi) + V2(random.uniform(-0.3, 0.3), random.uniform(-0.1, 0.1));
        if (random.unit() < 0.5) {
          const double r = random.uniform(0.1, 0.15);
          scene.addSphere(V3(c.x(), c.y(), top + r), r, randomTexture(random, 0.05, 0.1),
                          prefix + "ball " + std::to_string(++balls));
        } else {
          const double s = random.uniform(0.2, 0.3);
          scene.addBox(V3(c.x() - 0.5 * s, c.y() - 0.5 * s, top),
                       V3(c.x() + 0.5 * s, c.y() + 0.5 * s, top + s),
                       randomTexture(random, 0.04, 0.08),
                       prefix + "box on desk " + std::to_string(desks));
        }
      }
    } else if (type <= 8) {
      scene.addBox(V3(lo.x(), lo.y(), 0.0), V3(hi.x(), hi.y(), top),
                   randomTexture(random, type <= 6 ? 0.12 : 0.06, type <= 6 ? 0.25 : 0.12),
                   prefix + (type <= 6 ? "cabinet " + std::to_string(++cabinets)
                                       : "crate " + std::to_string(++crates)));
    } else {
      const double r = 0.5 * along;
      const V2 c = 0.5 * (lo + hi);
      scene.addSphere(V3(c.x(), c.y(), r), r, randomTexture(random, 0.06, 0.14),
                      prefix + "ball " + std::to_string(++balls));
    }
    placed.push_back({lo, hi});
  }
}

}  // namespace

std::string buildingProblem(const BuildingOptions& o) {
  char text[200];
  const double min_width = kMinCorridor + 2.0 * kCorridorWall + 2.0 * kMinRoomDepth;
  if (!(o.length >= 8.0 && o.length <= 200.0 && o.width >= min_width && o.width <= 200.0)) {
    std::snprintf(text, sizeof(text),
                  "a building of %.1f x %.1f m does not fit two rows of rooms and a corridor (at "
                  "least 8 x %.1f m, at most 200 x 200 m)",
                  o.length, o.width, min_width);
    return text;
  }
  if (!(o.height >= 2.4 && o.height <= 5.0)) {
    std::snprintf(text, sizeof(text), "a building's height of %.2f m is outside 2.4 to 5 m",
                  o.height);
    return text;
  }
  return "";
}

SyntheticScene generateBuilding(const BuildingOptions& o) {
  const std::string problem = buildingProblem(o);
  if (!problem.empty()) throw InputError("synthetic building: " + problem);
  Random random(o.seed);
  const double L = o.length, W = o.width, H = o.height;
  SyntheticScene scene;
  // The shell: floor, ceiling and outer walls, in the rooms' warm checker.
  scene.addRoom(V3(-0.5 * L, -0.5 * W, 0.0), V3(0.5 * L, 0.5 * W, H),
                makeTexture(SurfaceTexture::Pattern::kChecker, {225, 210, 180}, {90, 70, 60}, 0.25),
                "building");

  // The corridor: 2 to 2.4 m wide, a little off the middle so the two rows differ in depth.
  const double widest = W - 2.0 * kCorridorWall - 2.0 * kMinRoomDepth;  // buildingProblem: >= 2
  const double corridor = std::min(random.uniform(kMinCorridor, kMinCorridor + 0.4), widest);
  const double avail = W - corridor - 2.0 * kCorridorWall;
  const double south_depth =
      std::clamp(random.uniform(0.4, 0.6) * avail, kMinRoomDepth, avail - kMinRoomDepth);
  const double south_wall = -0.5 * W + south_depth + 0.5 * kCorridorWall;  // centre lines
  const double corridor_y = south_wall + 0.5 * kCorridorWall + 0.5 * corridor;
  const double north_wall = corridor_y + 0.5 * corridor + 0.5 * kCorridorWall;
  const double door_height = std::min(kDoorHeight, H - 0.3);

  FloorPlan plan;
  plan.corridor_from = V2(-0.5 * L + kEndClearance, corridor_y);
  plan.corridor_to = V2(0.5 * L - kEndClearance, corridor_y);
  plan.camera_height = std::min(1.4, 0.5 * H + 0.1);

  std::vector<PlanRoom> rooms;
  for (const int side : {-1, 1}) {
    const char row = side < 0 ? 'S' : 'N';
    const double wall_y = side < 0 ? south_wall : north_wall;
    const double face_y = wall_y + side * 0.5 * kCorridorWall;  // the wall's face in the rooms
    const double outer_y = side * 0.5 * W;
    // Rooms 4 to 5.5 m wide on average, each at least 3 m: 3 m each plus a random share of
    // what is left.
    const int most = static_cast<int>(std::floor((L + kPartition) / (kMinRoomWidth + kPartition)));
    const int count =
        std::clamp(static_cast<int>(std::lround(L / random.uniform(4.0, 5.5))), 1, most);
    std::vector<double> widths(static_cast<std::size_t>(count));
    double sum = 0.0;
    for (double& w : widths) sum += (w = random.uniform(1.0, 3.0));
    const double spare = L - (count - 1) * kPartition - count * kMinRoomWidth;
    for (double& w : widths) w = kMinRoomWidth + spare * w / sum;
    double x = -0.5 * L;
    for (int i = 0; i < count; ++i) {
      const double x0 = x, x1 = x + widths[static_cast<std::size_t>(i)];
      x = x1 + kPartition;
      PlanRoom room;
      room.name = std::string(1, row) + std::to_string(i + 1);
      room.min = V2(x0, std::min(face_y, outer_y));
      room.max = V2(x1, std::max(face_y, outer_y));
      // The door: anywhere with wall on both sides of it and a tour's turn inside the corridor.
      const double door_width = random.uniform(1.2, 1.3);
      const double lo = std::max(x0 + kJambClearance + 0.5 * door_width, plan.corridor_from.x());
      const double hi = std::min(x1 - kJambClearance - 0.5 * door_width, plan.corridor_to.x());
      const double door_x = lo <= hi ? random.uniform(lo, hi) : 0.5 * (x0 + x1);
      room.door = V2(door_x, wall_y);
      // Stops on the way in, one per 4.5 m of depth, so every wall is within the sensor's range.
      const double depth = room.max.y() - room.min.y();
      const int stops = std::max(1, static_cast<int>(std::ceil(depth / kStopSpacing)));
      for (int k = 0; k < stops; ++k)
        room.stops.emplace_back(door_x, face_y + side * (k + 0.5) * depth / stops);

      // The corridor wall in front of the room (partition centre to partition centre, or the
      // outer wall), with its door, and the partition to the next room.
      SceneWall front;
      front.name = room.name + " corridor wall";
      front.from = V2(i == 0 ? -0.5 * L : x0 - 0.5 * kPartition, wall_y);
      front.to = V2(i == count - 1 ? 0.5 * L : x1 + 0.5 * kPartition, wall_y);
      front.height = H;
      front.thickness = kCorridorWall;
      front.doors.push_back({door_x - front.from.x(), door_width, door_height});
      front.texture = randomTexture(random, 0.15, 0.3);
      scene.addWall(front);
      if (i + 1 < count) {
        SceneWall partition;
        partition.name = room.name + " partition";
        partition.from = V2(x1 + 0.5 * kPartition, face_y);
        partition.to = V2(x1 + 0.5 * kPartition, outer_y);
        partition.height = H;
        partition.thickness = kPartition;
        partition.texture = randomTexture(random, 0.15, 0.3);
        scene.addWall(partition);
      }
      furnish(scene, room, H, random);
      rooms.push_back(room);
    }
  }
  plan.rooms = rooms;
  scene.setFloorPlan(plan);
  return scene;
}

}  // namespace rgbdmap
