#include "rgbdmap/sim/synthetic_scene.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <utility>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {
namespace {

constexpr double kMinHitDistance = 1e-9;
// m: the ground grid's cells, about a piece of furniture; a ray crosses a few before it hits.
constexpr double kGridCell = 1.0;

// A well-mixed 64-bit hash of a texture cell (splitmix64 finaliser), mapped to [0, 1).
double cellNoise(std::int64_t i, std::int64_t j) {
  std::uint64_t x = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^
                    (static_cast<std::uint64_t>(j) + 0x632BE59BD9B4E019ull);
  x ^= x >> 30;
  x *= 0xBF58476D1CE4E5B9ull;
  x ^= x >> 27;
  x *= 0x94D049BB133111EBull;
  x ^= x >> 31;
  return static_cast<double>(x >> 11) * (1.0 / 9007199254740992.0);
}

std::int64_t floorIndex(double x) { return static_cast<std::int64_t>(std::floor(x)); }

// Smooth random values in [0, 1] (value noise: random lattice values, smoothstep-interpolated).
double valueNoise(double x, double y) {
  const std::int64_t i = floorIndex(x), j = floorIndex(y);
  const double fx = x - static_cast<double>(i), fy = y - static_cast<double>(j);
  const double sx = fx * fx * (3.0 - 2.0 * fx), sy = fy * fy * (3.0 - 2.0 * fy);
  // Offsets keep the lattice's values independent of the pattern cells' cellNoise.
  const double a = cellNoise(i + 7919, j - 104729), b = cellNoise(i + 7920, j - 104729);
  const double c = cellNoise(i + 7919, j - 104728), d = cellNoise(i + 7920, j - 104728);
  return (a * (1.0 - sx) + b * sx) * (1.0 - sy) + (c * (1.0 - sx) + d * sx) * sy;
}

// Slab test of a ray against an axis-aligned box's surface. Hits the entry face when the origin
// is outside and the exit face when it is inside (the room is seen from within).
bool hitBox(const ScenePrimitive& box, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
            double& t, int& axis) {
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  int near_axis = -1, far_axis = -1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (o[k] < box.min[k] || o[k] > box.max[k]) return false;
      continue;
    }
    double t1 = (box.min[k] - o[k]) / d[k];
    double t2 = (box.max[k] - o[k]) / d[k];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > t_near) {
      t_near = t1;
      near_axis = k;
    }
    if (t2 < t_far) {
      t_far = t2;
      far_axis = k;
    }
  }
  if (t_near > t_far) return false;
  if (t_near > kMinHitDistance) {
    t = t_near;
    axis = near_axis;
    return true;
  }
  if (t_far > kMinHitDistance) {
    t = t_far;
    axis = far_axis;
    return true;
  }
  return false;
}

bool hitSphere(const ScenePrimitive& sphere, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
               double& t) {
  const Eigen::Vector3d oc = o - sphere.center;
  const double a = d.squaredNorm();
  const double b = oc.dot(d);
  const double c = oc.squaredNorm() - sphere.radius * sphere.radius;
  const double disc = b * b - a * c;
  if (disc < 0.0) return false;
  const double root = std::sqrt(disc);
  const double t1 = (-b - root) / a;
  const double t2 = (-b + root) / a;
  if (t1 > kMinHitDistance) {
    t = t1;
    return true;
  }
  if (t2 > kMinHitDistance) {
    t = t2;
    return true;
  }
  return false;
}

// Distance to the six faces of an axis-aligned box, from inside or outside.
double boxSurfaceDistance(const ScenePrimitive& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d center = 0.5 * (box.min + box.max);
  const Eigen::Vector3d half = 0.5 * (box.max - box.min);
  const Eigen::Vector3d q = (p - center).cwiseAbs() - half;
  if ((q.array() > 0.0).any()) return q.cwiseMax(0.0).norm();
  return -q.maxCoeff();
}

bool insideBox(const ScenePrimitive& box, const Eigen::Vector3d& p) {
  return (p.array() > box.min.array()).all() && (p.array() < box.max.array()).all();
}

const char* kindName(ScenePrimitive::Kind kind) {
  switch (kind) {
    case ScenePrimitive::Kind::kRoom:
      return "room";
    case ScenePrimitive::Kind::kBox:
      return "box";
    case ScenePrimitive::Kind::kSphere:
      return "sphere";
  }
  return "?";
}

const char* patternName(SurfaceTexture::Pattern pattern) {
  switch (pattern) {
    case SurfaceTexture::Pattern::kChecker:
      return "checker";
    case SurfaceTexture::Pattern::kStripes:
      return "stripes";
    case SurfaceTexture::Pattern::kWaves:
      return "waves";
  }
  return "?";
}

YAML::Node vectorNode(const Eigen::Vector3d& v) {
  YAML::Node node(YAML::NodeType::Sequence);
  for (int i = 0; i < 3; ++i) node.push_back(v[i]);
  node.SetStyle(YAML::EmitterStyle::Flow);
  return node;
}

YAML::Node colorNode(const cv::Vec3b& c) {
  YAML::Node node(YAML::NodeType::Sequence);
  for (int i = 0; i < 3; ++i) node.push_back(static_cast<int>(c[i]));
  node.SetStyle(YAML::EmitterStyle::Flow);
  return node;
}

YAML::Node vectorNode(const Eigen::Vector2d& v) {
  YAML::Node node(YAML::NodeType::Sequence);
  for (int i = 0; i < 2; ++i) node.push_back(v[i]);
  node.SetStyle(YAML::EmitterStyle::Flow);
  return node;
}

YAML::Node textureNode(const SurfaceTexture& t) {
  YAML::Node texture;
  texture["pattern"] = patternName(t.pattern);
  texture["color_a"] = colorNode(t.color_a);
  texture["color_b"] = colorNode(t.color_b);
  texture["scale"] = t.scale;
  texture["angle_deg"] = t.angle_deg;
  return texture;
}

// Reading scene.yaml: every problem becomes "file:line: what".
class SceneReader {
 public:
  explicit SceneReader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const YAML::Node& node, const std::string& what) const {
    const YAML::Mark mark = node.Mark();
    if (mark.is_null()) throw InputError(path_ + ": " + what);
    throw InputError(where(path_, static_cast<std::size_t>(mark.line) + 1) + ": " + what);
  }

  const YAML::Node field(const YAML::Node& map, const char* key, const std::string& owner) const {
    const YAML::Node node = map[key];
    if (!node) fail(map, owner + " has no '" + key + "'");
    return node;
  }

  double number(const YAML::Node& map, const char* key, const std::string& owner) const {
    const YAML::Node node = field(map, key, owner);
    double value = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value))
      fail(node, owner + "." + key + " is not a number");
    return value;
  }

  Eigen::Vector3d vector(const YAML::Node& map, const char* key, const std::string& owner) const {
    const YAML::Node node = field(map, key, owner);
    if (!node.IsSequence() || node.size() != 3)
      fail(node, owner + "." + key + " must be a list of 3 numbers [x, y, z]");
    Eigen::Vector3d v;
    for (std::size_t i = 0; i < 3; ++i) {
      if (!node[i].IsScalar() || !YAML::convert<double>::decode(node[i], v[i]) ||
          !std::isfinite(v[i]))
        fail(node, owner + "." + key + " must be a list of 3 numbers [x, y, z]");
    }
    return v;
  }

  Eigen::Vector2d vector2(const YAML::Node& map, const char* key, const std::string& owner) const {
    return point2(field(map, key, owner), owner + "." + key);
  }

  Eigen::Vector2d point2(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence() || node.size() != 2)
      fail(node, what + " must be a list of 2 numbers [x, y]");
    Eigen::Vector2d v;
    for (std::size_t i = 0; i < 2; ++i) {
      if (!node[i].IsScalar() || !YAML::convert<double>::decode(node[i], v[i]) ||
          !std::isfinite(v[i]))
        fail(node, what + " must be a list of 2 numbers [x, y]");
    }
    return v;
  }

  // floor_plan: {corridor: {from, to}, camera_height, rooms: [{name, min, max, door, stops}]}
  FloorPlan floorPlan(const YAML::Node& node) const {
    if (!node.IsMap()) fail(node, "floor_plan must be a map");
    FloorPlan plan;
    const YAML::Node corridor = field(node, "corridor", "floor_plan");
    if (!corridor.IsMap()) fail(corridor, "floor_plan.corridor must be a map {from, to}");
    plan.corridor_from = vector2(corridor, "from", "floor_plan.corridor");
    plan.corridor_to = vector2(corridor, "to", "floor_plan.corridor");
    if (plan.corridor_from.y() != plan.corridor_to.y() ||
        plan.corridor_from.x() == plan.corridor_to.x())
      fail(corridor, "floor_plan.corridor must run along x (from and to share y)");
    if (node["camera_height"]) plan.camera_height = number(node, "camera_height", "floor_plan");
    if (!(plan.camera_height > 0.0)) fail(node, "floor_plan.camera_height must be positive");
    const YAML::Node rooms = node["rooms"];
    if (rooms && !rooms.IsSequence()) fail(rooms, "floor_plan.rooms must be a list");
    for (std::size_t k = 0; rooms && k < rooms.size(); ++k) {
      const YAML::Node r = rooms[k];
      const std::string owner = "floor_plan.rooms[" + std::to_string(k) + "]";
      if (!r.IsMap()) fail(r, owner + " must be a map");
      PlanRoom room;
      room.name = r["name"] ? r["name"].as<std::string>("") : "room " + std::to_string(k);
      room.min = vector2(r, "min", owner);
      room.max = vector2(r, "max", owner);
      if (!(room.min.array() < room.max.array()).all())
        fail(r, owner + ": min must be below max on both axes");
      room.door = vector2(r, "door", owner);
      if (room.door.x() < room.min.x() || room.door.x() > room.max.x())
        fail(r, owner + ": its door is not beside it (door x outside the room's)");
      const YAML::Node stops = field(r, "stops", owner);
      if (!stops.IsSequence() || stops.size() == 0)
        fail(stops, owner + ".stops must be a non-empty list of [x, y]");
      for (std::size_t i = 0; i < stops.size(); ++i) {
        const Eigen::Vector2d stop = point2(stops[i], owner + ".stops[" + std::to_string(i) + "]");
        if (!((stop.array() > room.min.array()).all() && (stop.array() < room.max.array()).all()))
          fail(stops, owner + ".stops[" + std::to_string(i) + "] is not inside the room");
        room.stops.push_back(stop);
      }
      plan.rooms.push_back(room);
    }
    return plan;
  }

  cv::Vec3b color(const YAML::Node& map, const char* key, const std::string& owner) const {
    const YAML::Node node = field(map, key, owner);
    const std::string what = owner + "." + key + " must be [r, g, b] with values 0..255";
    if (!node.IsSequence() || node.size() != 3) fail(node, what);
    cv::Vec3b c;
    for (std::size_t i = 0; i < 3; ++i) {
      int value = -1;
      if (!node[i].IsScalar() || !YAML::convert<int>::decode(node[i], value) || value < 0 ||
          value > 255)
        fail(node, what);
      c[static_cast<int>(i)] = static_cast<unsigned char>(value);
    }
    return c;
  }

  SurfaceTexture texture(const YAML::Node& map, const std::string& owner) const {
    const YAML::Node node = field(map, "texture", owner);
    if (!node.IsMap()) fail(node, owner + ".texture must be a map");
    const std::string name = owner + ".texture";
    SurfaceTexture texture;
    const std::string pattern = field(node, "pattern", name).as<std::string>("");
    if (pattern == "checker") {
      texture.pattern = SurfaceTexture::Pattern::kChecker;
    } else if (pattern == "stripes") {
      texture.pattern = SurfaceTexture::Pattern::kStripes;
    } else if (pattern == "waves") {
      texture.pattern = SurfaceTexture::Pattern::kWaves;
    } else {
      fail(node["pattern"],
           name + ".pattern '" + pattern + "' is unknown (expected checker, stripes or waves)");
    }
    texture.color_a = color(node, "color_a", name);
    texture.color_b = color(node, "color_b", name);
    texture.scale = number(node, "scale", name);
    if (texture.scale <= 0.0) fail(node["scale"], name + ".scale must be positive");
    if (node["angle_deg"]) texture.angle_deg = number(node, "angle_deg", name);
    return texture;
  }

 private:
  std::string path_;
};

}  // namespace

cv::Vec3b SurfaceTexture::colorAt(double u, double v) const {
  double weight = 0.0;      // 0: colour a, 1: colour b
  double brightness = 1.0;  // per-cell variation that breaks the pattern's periodicity
  switch (pattern) {
    case Pattern::kChecker: {
      const std::int64_t i = floorIndex(u / scale), j = floorIndex(v / scale);
      weight = static_cast<double>((i + j) & 1);
      brightness = 0.72 + 0.28 * cellNoise(i, j);
      break;
    }
    case Pattern::kStripes: {
      const double a = angle_deg * M_PI / 180.0;
      const double across = u * std::cos(a) + v * std::sin(a);
      const double along = -u * std::sin(a) + v * std::cos(a);
      const std::int64_t i = floorIndex(across / scale);
      weight = static_cast<double>(i & 1);
      // Blocks along each stripe differ in brightness, so stripes also have gradients along.
      brightness = 0.72 + 0.28 * cellNoise(i, floorIndex(along / (3.0 * scale)));
      break;
    }
    case Pattern::kWaves: {
      // Two incommensurate waves: smooth gradients everywhere, no exact repetition.
      weight = 0.5 + 0.25 * std::sin(2.0 * M_PI * u / scale) +
               0.25 * std::sin(2.0 * M_PI * (0.6 * u + 0.8 * v) / (1.7 * scale));
      break;
    }
  }
  // A fine grain (3 cm) over every pattern, as real surfaces have: without it the inside of
  // a checker square is flat and image alignment only has the squares' edges to work with.
  brightness *= 0.8 + 0.4 * valueNoise(u / 0.03, v / 0.03);
  cv::Vec3b out;
  for (int c = 0; c < 3; ++c) {
    const double value = brightness * ((1.0 - weight) * color_a[c] + weight * color_b[c]);
    out[c] = static_cast<unsigned char>(std::clamp(std::lround(value), 0l, 255l));
  }
  return out;
}

void SyntheticScene::addPrimitive(const ScenePrimitive& primitive) {
  primitives_.push_back(primitive);
  // The grid is rebuilt with every primitive: a scene is built once and then queried by many
  // threads, and a few hundred primitives rebuild in microseconds.
  std::vector<Eigen::Vector4d> footprints;
  footprints.reserve(primitives_.size());
  rooms_.clear();
  const Eigen::Vector4d none = Eigen::Vector4d::Constant(std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < primitives_.size(); ++k) {
    const ScenePrimitive& p = primitives_[k];
    if (p.kind == ScenePrimitive::Kind::kRoom) {
      rooms_.push_back(static_cast<std::uint32_t>(k));
      footprints.push_back(none);
    } else if (p.kind == ScenePrimitive::Kind::kSphere) {
      footprints.emplace_back(p.center.x() - p.radius, p.center.y() - p.radius,
                              p.center.x() + p.radius, p.center.y() + p.radius);
    } else {
      footprints.emplace_back(p.min.x(), p.min.y(), p.max.x(), p.max.y());
    }
  }
  grid_.build(footprints, kGridCell);
}

void SyntheticScene::addRoom(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                             const SurfaceTexture& texture, const std::string& name) {
  ScenePrimitive room;
  room.kind = ScenePrimitive::Kind::kRoom;
  room.min = min;
  room.max = max;
  room.texture = texture;
  room.name = name;
  addPrimitive(room);
}

void SyntheticScene::addBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                            const SurfaceTexture& texture, const std::string& name) {
  ScenePrimitive box;
  box.kind = ScenePrimitive::Kind::kBox;
  box.min = min;
  box.max = max;
  box.texture = texture;
  box.name = name;
  addPrimitive(box);
}

void SyntheticScene::addSphere(const Eigen::Vector3d& center, double radius,
                               const SurfaceTexture& texture, const std::string& name) {
  ScenePrimitive sphere;
  sphere.kind = ScenePrimitive::Kind::kSphere;
  sphere.center = center;
  sphere.radius = radius;
  sphere.texture = texture;
  sphere.name = name;
  addPrimitive(sphere);
}

std::string SyntheticScene::wallProblem(const SceneWall& wall) {
  const bool finite = wall.from.allFinite() && wall.to.allFinite() && std::isfinite(wall.base) &&
                      std::isfinite(wall.height) && std::isfinite(wall.thickness);
  if (!finite) return "its coordinates and sizes must be finite numbers";
  const bool along_x = wall.from.x() != wall.to.x(), along_y = wall.from.y() != wall.to.y();
  if (along_x == along_y)
    return along_x ? "it runs neither along x nor along y (from and to must share x or y)"
                   : "from and to are the same point";
  if (wall.height <= 0.0) return "its height must be positive";
  if (wall.thickness <= 0.0) return "its thickness must be positive";
  const double length = (wall.to - wall.from).norm();
  std::vector<std::pair<double, double>> openings;
  for (std::size_t k = 0; k < wall.doors.size(); ++k) {
    const WallDoor& door = wall.doors[k];
    const std::string which = "door " + std::to_string(k);
    if (!std::isfinite(door.at) || !(door.width > 0.0) || !(door.height > 0.0) ||
        !std::isfinite(door.width) || !std::isfinite(door.height))
      return which + ": at must be a number, width and height positive";
    const double lo = door.at - 0.5 * door.width, hi = door.at + 0.5 * door.width;
    if (lo < -1e-9 || hi > length + 1e-9) {
      char text[160];
      std::snprintf(text, sizeof(text), "%s (%.3f to %.3f m along it) lies outside the %.3f m wall",
                    which.c_str(), lo, hi, length);
      return text;
    }
    openings.emplace_back(lo, hi);
  }
  std::sort(openings.begin(), openings.end());
  for (std::size_t k = 1; k < openings.size(); ++k)
    if (openings[k].first < openings[k - 1].second) return "two of its doors overlap";
  return "";
}

void SyntheticScene::addWall(const SceneWall& wall) {
  const std::string problem = wallProblem(wall);
  if (!problem.empty()) throw std::invalid_argument("wall '" + wall.name + "': " + problem);
  const int index = static_cast<int>(walls_.size());
  walls_.push_back(wall);
  const int a = wall.from.x() != wall.to.x() ? 0 : 1;  // the axis it runs along
  const int c = 1 - a;
  const double sign = wall.to[a] > wall.from[a] ? 1.0 : -1.0;
  const double top = wall.base + wall.height;
  struct Opening {
    double lo, hi, top;
  };
  std::vector<Opening> openings;
  for (const WallDoor& door : wall.doors) {
    const double centre = wall.from[a] + sign * door.at;
    openings.push_back({centre - 0.5 * door.width, centre + 0.5 * door.width,
                        wall.base + std::min(door.height, wall.height)});
  }
  std::sort(openings.begin(), openings.end(),
            [](const Opening& l, const Opening& r) { return l.lo < r.lo; });
  int pieces = 0;
  auto piece = [&](double lo, double hi, double z0, double z1, const char* what) {
    if (hi - lo <= 1e-9 || z1 - z0 <= 1e-9) return;
    ScenePrimitive box;
    box.kind = ScenePrimitive::Kind::kBox;
    box.min[a] = lo;
    box.max[a] = hi;
    box.min[c] = wall.from[c] - 0.5 * wall.thickness;
    box.max[c] = wall.from[c] + 0.5 * wall.thickness;
    box.min.z() = z0;
    box.max.z() = z1;
    box.texture = wall.texture;
    box.name = wall.name + " (" + what + " " + std::to_string(pieces++) + ")";
    box.wall = index;
    addPrimitive(box);
  };
  double at = std::min(wall.from[a], wall.to[a]);
  for (const Opening& opening : openings) {
    piece(at, opening.lo, wall.base, top, "piece");
    piece(opening.lo, opening.hi, opening.top, top, "lintel");
    at = opening.hi;
  }
  piece(at, std::max(wall.from[a], wall.to[a]), wall.base, top, "piece");
}

const ScenePrimitive& SyntheticScene::room() const {
  for (const ScenePrimitive& p : primitives_)
    if (p.kind == ScenePrimitive::Kind::kRoom) return p;
  throw std::logic_error("synthetic scene has no room");
}

bool SyntheticScene::hitPrimitive(std::size_t index, const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& direction, double& t, int& axis) const {
  const ScenePrimitive& p = primitives_[index];
  return p.kind == ScenePrimitive::Kind::kSphere ? hitSphere(p, origin, direction, t)
                                                 : hitBox(p, origin, direction, t, axis);
}

void SyntheticScene::shade(std::size_t index, int axis, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& direction, double t, Eigen::Vector3d& normal,
                           cv::Vec3b& color) const {
  const ScenePrimitive* hit = &primitives_[index];
  const Eigen::Vector3d point = origin + t * direction;
  double u = 0.0, v = 0.0;
  if (hit->kind == ScenePrimitive::Kind::kSphere) {
    normal = (point - hit->center) / hit->radius;
    // Longitude and latitude as arc lengths, so texture scale is in metres as on the boxes.
    u = hit->radius * std::atan2(normal.y(), normal.x());
    v = hit->radius * std::asin(std::clamp(normal.z(), -1.0, 1.0));
  } else {
    normal = Eigen::Vector3d::Zero();
    normal[axis] = 1.0;
    u = point[(axis + 1) % 3];
    v = point[(axis + 2) % 3];
  }
  if (normal.dot(direction) > 0.0) normal = -normal;
  const cv::Vec3b rgb = hit->texture.colorAt(u, v);
  color = cv::Vec3b(rgb[2], rgb[1], rgb[0]);
}

bool SyntheticScene::raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                             double& t, Eigen::Vector3d& normal, cv::Vec3b& color) const {
  // The nearest hit, ties to the primitive listed first (as testing every primitive in order).
  double best = std::numeric_limits<double>::infinity();
  std::size_t hit = std::numeric_limits<std::size_t>::max();
  int hit_axis = -1;
  auto consider = [&](std::size_t k) {
    double t_hit = 0.0;
    int axis = -1;
    if (hitPrimitive(k, origin, direction, t_hit, axis) &&
        (t_hit < best || (t_hit == best && k < hit))) {
      best = t_hit;
      hit = k;
      hit_axis = axis;
    }
  };
  for (const std::uint32_t k : rooms_) consider(k);
  // Whatever the cells beyond hold is farther than a hit before the ray leaves this one (a
  // hair's margin keeps a hit on a cell border from being decided by rounding).
  grid_.walkRay(origin, direction,
                [&](const std::uint32_t* first, const std::uint32_t* last, double t_exit) {
                  for (const std::uint32_t* k = first; k != last; ++k) consider(*k);
                  return !(best + 1e-9 < t_exit);
                });
  if (hit == std::numeric_limits<std::size_t>::max()) return false;
  t = best;
  shade(hit, hit_axis, origin, direction, t, normal, color);
  return true;
}

bool SyntheticScene::raycastEveryPrimitive(const Eigen::Vector3d& origin,
                                           const Eigen::Vector3d& direction, double& t,
                                           Eigen::Vector3d& normal, cv::Vec3b& color) const {
  double best = std::numeric_limits<double>::infinity();
  std::size_t hit = std::numeric_limits<std::size_t>::max();
  int hit_axis = -1;
  for (std::size_t k = 0; k < primitives_.size(); ++k) {
    double t_hit = 0.0;
    int axis = -1;
    if (hitPrimitive(k, origin, direction, t_hit, axis) && t_hit < best) {
      best = t_hit;
      hit = k;
      hit_axis = axis;
    }
  }
  if (hit == std::numeric_limits<std::size_t>::max()) return false;
  t = best;
  shade(hit, hit_axis, origin, direction, t, normal, color);
  return true;
}

double SyntheticScene::primitiveDistance(std::size_t index, const Eigen::Vector3d& p) const {
  const ScenePrimitive& primitive = primitives_[index];
  return primitive.kind == ScenePrimitive::Kind::kSphere
             ? std::abs((p - primitive.center).norm() - primitive.radius)
             : boxSurfaceDistance(primitive, p);
}

double SyntheticScene::distance(const Eigen::Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const std::uint32_t k : rooms_) best = std::min(best, primitiveDistance(k, p));
  // Rings of cells round p's, until every primitive not yet seen is farther on the ground alone.
  for (int ring = 0;; ++ring) {
    const double beyond = grid_.visitRing(
        p.x(), p.y(), ring, [&](const std::uint32_t* first, const std::uint32_t* last) {
          for (const std::uint32_t* k = first; k != last; ++k)
            best = std::min(best, primitiveDistance(*k, p));
        });
    if (beyond < 0.0) {
      if (ring == 0 && !grid_.empty()) return distanceEveryPrimitive(p);  // p is off the grid
      break;
    }
    if (best <= beyond) break;
  }
  return best;
}

double SyntheticScene::distanceEveryPrimitive(const Eigen::Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < primitives_.size(); ++k)
    best = std::min(best, primitiveDistance(k, p));
  return best;
}

bool SyntheticScene::isFreeSpace(const Eigen::Vector3d& p, double margin) const {
  bool in_room = false;
  for (const std::uint32_t k : rooms_)
    if (insideBox(primitives_[k], p)) in_room = true;
  if (!in_room) return false;
  bool inside_object = false;
  grid_.visitCellAt(p.x(), p.y(), [&](const std::uint32_t* first, const std::uint32_t* last) {
    for (const std::uint32_t* k = first; k != last; ++k) {
      const ScenePrimitive& primitive = primitives_[*k];
      if (primitive.kind == ScenePrimitive::Kind::kSphere
              ? (p - primitive.center).norm() < primitive.radius
              : insideBox(primitive, p))
        inside_object = true;
    }
  });
  return !inside_object && distance(p) >= margin;
}

void SyntheticScene::save(const std::string& path) const {
  YAML::Node root;
  root["format"] = "rgbdmap synthetic scene 1";
  root["units"] = "metres; world z up; colours RGB";
  int written_wall = -1;
  for (const ScenePrimitive& p : primitives_) {
    // A wall is written once, where its first box is, so reading it back keeps every primitive
    // in its place (the order decides which of two coincident faces a ray sees).
    if (p.wall >= 0) {
      if (p.wall == written_wall) continue;
      written_wall = p.wall;
      const SceneWall& wall = walls_[static_cast<std::size_t>(p.wall)];
      YAML::Node node;
      node["kind"] = "wall";
      node["name"] = wall.name;
      node["from"] = vectorNode(wall.from);
      node["to"] = vectorNode(wall.to);
      node["base"] = wall.base;
      node["height"] = wall.height;
      node["thickness"] = wall.thickness;
      for (const WallDoor& door : wall.doors) {
        YAML::Node d;
        d["at"] = door.at;
        d["width"] = door.width;
        d["height"] = door.height;
        d.SetStyle(YAML::EmitterStyle::Flow);
        node["doors"].push_back(d);
      }
      node["texture"] = textureNode(wall.texture);
      root["primitives"].push_back(node);
      continue;
    }
    YAML::Node node;
    node["kind"] = kindName(p.kind);
    node["name"] = p.name;
    if (p.kind == ScenePrimitive::Kind::kSphere) {
      node["center"] = vectorNode(p.center);
      node["radius"] = p.radius;
    } else {
      node["min"] = vectorNode(p.min);
      node["max"] = vectorNode(p.max);
    }
    node["texture"] = textureNode(p.texture);
    root["primitives"].push_back(node);
  }
  if (plan_) {
    YAML::Node plan;
    plan["corridor"]["from"] = vectorNode(plan_->corridor_from);
    plan["corridor"]["to"] = vectorNode(plan_->corridor_to);
    plan["corridor"].SetStyle(YAML::EmitterStyle::Flow);
    plan["camera_height"] = plan_->camera_height;
    for (const PlanRoom& room : plan_->rooms) {
      YAML::Node r;
      r["name"] = room.name;
      r["min"] = vectorNode(room.min);
      r["max"] = vectorNode(room.max);
      r["door"] = vectorNode(room.door);
      for (const Eigen::Vector2d& stop : room.stops) r["stops"].push_back(vectorNode(stop));
      r["stops"].SetStyle(YAML::EmitterStyle::Flow);
      plan["rooms"].push_back(r);
    }
    root["floor_plan"] = plan;
  }
  YAML::Emitter emitter;
  emitter.SetDoublePrecision(15);  // short decimals (0.6) read back exactly
  emitter << root;
  std::ofstream out(path);
  out << emitter.c_str() << '\n';
  out.flush();
  if (!out) throw std::runtime_error(path + ": cannot write the scene description");
}

SyntheticScene SyntheticScene::load(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path + ": cannot open the scene description");
  } catch (const YAML::Exception& e) {
    throw InputError(where(path, static_cast<std::size_t>(e.mark.line) + 1) +
                     ": not valid YAML: " + e.msg);
  }
  const SceneReader reader(path);
  if (!root.IsMap()) reader.fail(root, "expected a map with a list 'primitives'");
  const YAML::Node primitives = root["primitives"];
  if (!primitives || !primitives.IsSequence() || primitives.size() == 0)
    reader.fail(root, "expected a non-empty list 'primitives'");
  SyntheticScene scene;
  std::size_t rooms = 0;
  for (std::size_t i = 0; i < primitives.size(); ++i) {
    const YAML::Node node = primitives[i];
    std::string owner = "primitives[" + std::to_string(i) + "]";
    if (!node.IsMap()) reader.fail(node, owner + " must be a map");
    const std::string kind = reader.field(node, "kind", owner).as<std::string>("");
    const std::string name = node["name"] ? node["name"].as<std::string>("") : kind;
    owner += " (" + name + ")";
    const SurfaceTexture texture = reader.texture(node, owner);
    if (kind == "room" || kind == "box") {
      const Eigen::Vector3d min = reader.vector(node, "min", owner);
      const Eigen::Vector3d max = reader.vector(node, "max", owner);
      if (!(min.array() < max.array()).all())
        reader.fail(node, owner + ": min must be below max on every axis");
      if (kind == "room") {
        scene.addRoom(min, max, texture, name);
        ++rooms;
      } else {
        scene.addBox(min, max, texture, name);
      }
    } else if (kind == "sphere") {
      const double radius = reader.number(node, "radius", owner);
      if (radius <= 0.0) reader.fail(node["radius"], owner + ": radius must be positive");
      scene.addSphere(reader.vector(node, "center", owner), radius, texture, name);
    } else if (kind == "wall") {
      SceneWall wall;
      wall.name = name;
      wall.texture = texture;
      wall.from = reader.vector2(node, "from", owner);
      wall.to = reader.vector2(node, "to", owner);
      if (node["base"]) wall.base = reader.number(node, "base", owner);
      wall.height = reader.number(node, "height", owner);
      wall.thickness = reader.number(node, "thickness", owner);
      const YAML::Node doors = node["doors"];
      if (doors && !doors.IsSequence())
        reader.fail(doors, owner + ".doors must be a list of {at, width, height}");
      for (std::size_t k = 0; doors && k < doors.size(); ++k) {
        const std::string door = owner + ".doors[" + std::to_string(k) + "]";
        if (!doors[k].IsMap()) reader.fail(doors[k], door + " must be a map {at, width, height}");
        wall.doors.push_back({reader.number(doors[k], "at", door),
                              reader.number(doors[k], "width", door),
                              reader.number(doors[k], "height", door)});
      }
      const std::string problem = wallProblem(wall);
      if (!problem.empty()) reader.fail(node, owner + ": " + problem);
      scene.addWall(wall);
    } else {
      reader.fail(node,
                  owner + ": kind '" + kind + "' is unknown (expected room, box, sphere or wall)");
    }
  }
  if (rooms != 1)
    throw InputError(path + ": expected exactly one primitive of kind 'room', found " +
                     std::to_string(rooms));
  if (const YAML::Node plan = root["floor_plan"]) scene.setFloorPlan(reader.floorPlan(plan));
  return scene;
}

SyntheticScene SyntheticScene::defaultRoom() { return defaultRoom(Eigen::Vector3d(5.0, 4.0, 2.8)); }

SyntheticScene SyntheticScene::defaultRoom(const Eigen::Vector3d& size) {
  using Pattern = SurfaceTexture::Pattern;
  using V = Eigen::Vector3d;
  auto texture = [](Pattern pattern, cv::Vec3b a, cv::Vec3b b, double scale, double angle = 0.0) {
    SurfaceTexture t;
    t.pattern = pattern;
    t.color_a = a;
    t.color_b = b;
    t.scale = scale;
    t.angle_deg = angle;
    return t;
  };
  // The furniture is laid out for a 5 x 4 m floor; in another room each object's centre moves
  // with the walls (its x and y scale with the room's), its size and height stay.
  const V scale(size.x() / 5.0, size.y() / 4.0, 1.0);
  struct Scaled {
    SyntheticScene& scene;
    V scale;
    void addBox(const V& min, const V& max, const SurfaceTexture& t, const std::string& name) {
      const V shift = (0.5 * (min + max)).cwiseProduct(scale) - 0.5 * (min + max);
      scene.addBox(min + V(shift.x(), shift.y(), 0.0), max + V(shift.x(), shift.y(), 0.0), t, name);
    }
    void addSphere(const V& c, double r, const SurfaceTexture& t, const std::string& name) {
      scene.addSphere(V(c.x() * scale.x(), c.y() * scale.y(), c.z()), r, t, name);
    }
  };
  SyntheticScene room;
  // Floor, walls and ceiling share one checker of warm tones; 25 cm squares stay visible at 4 m.
  room.addRoom(V(-0.5 * size.x(), -0.5 * size.y(), 0.0),
               V(0.5 * size.x(), 0.5 * size.y(), size.z()),
               texture(Pattern::kChecker, {225, 210, 180}, {90, 70, 60}, 0.25));
  Scaled scene{room, scale};
  scene.addBox(V(0.6, -1.6, 0.0), V(1.8, -0.8, 0.75),
               texture(Pattern::kStripes, {150, 95, 45}, {235, 190, 120}, 0.06, 20.0), "table");
  scene.addBox(V(-2.5, 0.6, 0.0), V(-2.1, 1.6, 1.6),
               texture(Pattern::kWaves, {40, 90, 170}, {200, 225, 250}, 0.2), "cabinet");
  scene.addBox(V(-1.8, -1.5, 0.0), V(-1.3, -1.0, 0.5),
               texture(Pattern::kChecker, {200, 40, 40}, {250, 220, 90}, 0.1), "red cube");
  scene.addBox(V(-0.5, 1.2, 0.0), V(-0.1, 1.6, 0.4),
               texture(Pattern::kStripes, {30, 130, 60}, {210, 240, 200}, 0.05, -35.0),
               "green cube");
  scene.addBox(V(1.0, -1.4, 0.75), V(1.3, -1.1, 1.05),
               texture(Pattern::kChecker, {60, 60, 200}, {240, 240, 240}, 0.075), "cube on table");
  scene.addSphere(V(1.5, 1.2, 0.35), 0.35,
                  texture(Pattern::kChecker, {230, 120, 30}, {50, 30, 90}, 0.12), "ball");
  scene.addSphere(V(1.55, -0.95, 0.9), 0.15,
                  texture(Pattern::kWaves, {250, 250, 60}, {120, 30, 140}, 0.08), "ball on table");
  scene.addSphere(V(-1.55, -1.25, 0.75), 0.25,
                  texture(Pattern::kStripes, {20, 160, 180}, {250, 250, 250}, 0.06, 60.0),
                  "ball on cube");
  return room;
}

}  // namespace rgbdmap
