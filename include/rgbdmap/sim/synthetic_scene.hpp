#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rgbdmap/sim/floor_plan.hpp"
#include "rgbdmap/sim/primitive_grid.hpp"

namespace rgbdmap {

// A procedural colour pattern over a surface's 2D coordinates (u, v) in metres. The colour
// varies everywhere at a few centimetres' scale so RGB odometry has gradients to follow, and
// each cell gets its own brightness so the pattern does not repeat exactly (a perfectly
// periodic texture lets odometry lock onto the wrong period).
struct SurfaceTexture {
  enum class Pattern { kChecker, kStripes, kWaves };
  Pattern pattern = Pattern::kChecker;
  cv::Vec3b color_a{200, 200, 200};  // RGB
  cv::Vec3b color_b{60, 60, 60};     // RGB
  double scale = 0.2;                // m: checker square, stripe width, wave period
  double angle_deg = 0.0;            // stripe direction in the (u, v) plane

  // RGB colour at surface coordinates (u, v).
  cv::Vec3b colorAt(double u, double v) const;
};

// One exact surface of the scene. A room is the inside of an axis-aligned box (floor, walls,
// ceiling); a box is a solid axis-aligned box; a sphere is solid. Geometrically the room and a
// box are the same six rectangles; the kind says on which side the camera may be.
struct ScenePrimitive {
  enum class Kind { kRoom, kBox, kSphere };
  Kind kind = Kind::kBox;
  Eigen::Vector3d min = Eigen::Vector3d::Zero();  // room, box: corners
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // sphere
  double radius = 0.0;
  SurfaceTexture texture;
  std::string name;  // for messages and the YAML file
  int wall = -1;     // a piece of SyntheticScene::walls()[wall], or -1
};

// An opening in a wall from its foot up to `height` (a door: the wall goes on above it).
struct WallDoor {
  double at = 0.0;      // m from the wall's `from` end to the opening's centre
  double width = 1.0;   // m
  double height = 2.1;  // m; at least the wall's height: an opening to the top (no lintel)
};

// A straight wall along x or y, `thickness` thick about the line from `from` to `to`, from `base`
// up to base + height, with doors. It is made of boxes: one beside each door and one above it
// (the lintel), so both its faces, the door's jambs and the lintel's underside are surfaces.
struct SceneWall {
  Eigen::Vector2d from = Eigen::Vector2d::Zero();  // (x, y) of its ends, on its centre line
  Eigen::Vector2d to = Eigen::Vector2d::Zero();
  double base = 0.0;  // z of its foot
  double height = 2.8;
  double thickness = 0.12;
  std::vector<WallDoor> doors;
  SurfaceTexture texture;
  std::string name;
};

// A scene of exact primitives: ray casting for rendering, exact distance to the nearest surface
// for scoring maps, and a YAML description (scene.yaml) so a map can be scored later.
class SyntheticScene {
 public:
  void addRoom(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
               const SurfaceTexture& texture, const std::string& name = "room");
  void addBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max, const SurfaceTexture& texture,
              const std::string& name);
  void addSphere(const Eigen::Vector3d& center, double radius, const SurfaceTexture& texture,
                 const std::string& name);
  // Adds the wall's boxes; throws std::invalid_argument saying what is wrong (wallProblem).
  void addWall(const SceneWall& wall);
  // Empty if the wall can be built, else what is wrong with it (not along x or y, a door
  // outside it or overlapping another, a size that is not positive).
  static std::string wallProblem(const SceneWall& wall);
  const std::vector<SceneWall>& walls() const { return walls_; }

  // The corridor and rooms a camera tour visits (a building's), if the scene has them.
  void setFloorPlan(const FloorPlan& plan) { plan_ = plan; }
  const FloorPlan* floorPlan() const { return plan_ ? &*plan_ : nullptr; }

  const std::vector<ScenePrimitive>& primitives() const { return primitives_; }
  // The room's bounds; throws std::logic_error if the scene has no room.
  const ScenePrimitive& room() const;

  // Nearest surface along origin + t * direction with t > 1e-9 (t is in units of |direction|,
  // so a camera ray with z = 1 yields depth along the optical axis). `normal` is the unit
  // surface normal facing the ray origin; `color` is the surface's texture colour in BGR
  // (OpenCV order), unlit. Returns false if the ray hits nothing.
  bool raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double& t,
               Eigen::Vector3d& normal, cv::Vec3b& color) const;
  // Exact unsigned distance from p to the nearest surface of any primitive.
  double distance(const Eigen::Vector3d& p) const;
  // The same two, testing every primitive instead of those the ground grid lists along the ray
  // or around p: the reference the grid is checked against (tests, benchmarks).
  bool raycastEveryPrimitive(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                             double& t, Eigen::Vector3d& normal, cv::Vec3b& color) const;
  double distanceEveryPrimitive(const Eigen::Vector3d& p) const;
  // True if p is inside the room, outside every box and sphere, and at least `margin` from
  // every surface: where a camera may be.
  bool isFreeSpace(const Eigen::Vector3d& p, double margin) const;

  // Writes the scene as YAML; throws std::runtime_error naming the file on failure.
  void save(const std::string& path) const;
  // Reads a scene written by save() (or by hand: docs/synthetic.md); throws InputError naming
  // the file (and line) and what is wrong.
  static SyntheticScene load(const std::string& path);

  // A 5 x 4 x 2.8 m room with a table, a cabinet, cubes on the floor and the table, and three
  // spheres; world z is up, the floor is z = 0, the room is centred on x = y = 0.
  static SyntheticScene defaultRoom();
  // The same furniture in a room of another size (x, y, z in metres, each at least 3 x 3 x 2):
  // the objects keep their sizes and heights, their places move with the walls.
  static SyntheticScene defaultRoom(const Eigen::Vector3d& size);

 private:
  void addPrimitive(const ScenePrimitive& primitive);
  // The nearest hit of primitive `index` (t, and the hit face's axis for boxes).
  bool hitPrimitive(std::size_t index, const Eigen::Vector3d& origin,
                    const Eigen::Vector3d& direction, double& t, int& axis) const;
  // Normal and colour of a hit of primitive `index` at t.
  void shade(std::size_t index, int axis, const Eigen::Vector3d& origin,
             const Eigen::Vector3d& direction, double t, Eigen::Vector3d& normal,
             cv::Vec3b& color) const;
  double primitiveDistance(std::size_t index, const Eigen::Vector3d& p) const;

  std::vector<ScenePrimitive> primitives_;
  std::vector<SceneWall> walls_;
  std::optional<FloorPlan> plan_;
  // Every primitive but the rooms, over the ground plane; the rooms are tested for every query.
  PrimitiveGrid grid_;
  std::vector<std::uint32_t> rooms_;
};

}  // namespace rgbdmap
