#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

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
  // True if p is inside the room, outside every box and sphere, and at least `margin` from
  // every surface: where a camera may be.
  bool isFreeSpace(const Eigen::Vector3d& p, double margin) const;

  // Writes the scene as YAML; throws std::runtime_error naming the file on failure.
  void save(const std::string& path) const;
  // Reads a scene written by save(); throws InputError naming the file (and line) and what is
  // wrong.
  static SyntheticScene load(const std::string& path);

  // A 5 x 4 x 2.8 m room with a table, a cabinet, cubes on the floor and the table, and three
  // spheres; world z is up, the floor is z = 0, the room is centred on x = y = 0.
  static SyntheticScene defaultRoom();
  // The same furniture in a room of another size (x, y, z in metres, each at least 3 x 3 x 2):
  // the objects keep their sizes and heights, their places move with the walls.
  static SyntheticScene defaultRoom(const Eigen::Vector3d& size);

 private:
  std::vector<ScenePrimitive> primitives_;
};

}  // namespace rgbdmap
