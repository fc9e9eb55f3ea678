#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rgbdmap/sim/floor_plan.hpp"
#include "rgbdmap/sim/synthetic_scene.hpp"

namespace rgbdmap {

// Where a synthetic camera is at time t: camera-to-world (x right, y down, z forward).
class CameraPath {
 public:
  virtual ~CameraPath() = default;
  virtual Eigen::Isometry3d pose(double t) const = 0;
};

// The camera at `position` looking along yaw (about +z, from +x) and pitch (up positive), then
// rolled about its optical axis: a hand-held camera whose "up" stays near the world's +z.
Eigen::Isometry3d handheldPose(const Eigen::Vector3d& position, double yaw, double pitch,
                               double roll);

// A slow circle round the room's centre at about half its height, looking outwards with
// sinusoidal sway in yaw, pitch and roll, so each surface is seen from several positions. Sums of
// sinusoids; the seed only shifts the phases of the small perturbations, so every seed keeps
// well clear of the scene's surfaces.
class HandheldPath : public CameraPath {
 public:
  // radius: of the circle (m, both axes); 0: 16% of the room's length and 15% of its width.
  HandheldPath(const ScenePrimitive& room, std::uint64_t seed, double loop_seconds,
               double radius = 0.0);
  Eigen::Isometry3d pose(double t) const override;

 private:
  Eigen::Vector3d center_;
  Eigen::Vector2d radius_;
  double loop_seconds_;
  double phase_[8];
};

// A walk round the room along its walls: a rectangle `inset` metres inside the walls with
// rounded corners, anticlockwise seen from above, one lap every `loop_seconds`, looking ahead
// and out towards the near wall (as someone filming the walls of a room), with a hand's sway.
// Each lap comes back to where the first began: the path for loop closure.
class WalkPath : public CameraPath {
 public:
  WalkPath(const ScenePrimitive& room, std::uint64_t seed, double loop_seconds, double inset);
  Eigen::Isometry3d pose(double t) const override;

 private:
  // Position and heading (rad) at arc length s along the lap.
  void along(double s, Eigen::Vector2d& position, double& heading) const;

  Eigen::Vector2d low_, high_;  // the rectangle the corners are rounded inside
  double corner_radius_, height_, loop_seconds_, lap_length_;
  double phase_[8];
};

// Once along one long wall, from one end to the other over `duration` seconds, filming it: a
// path that never comes back anywhere it has been (no loop to close).
class LinePath : public CameraPath {
 public:
  LinePath(const ScenePrimitive& room, std::uint64_t seed, double duration, double inset);
  Eigen::Isometry3d pose(double t) const override;

 private:
  Eigen::Vector3d start_, end_;
  double duration_;
  double phase_[8];
};

// A tour of an office floor: from the corridor's start along it, into every room in the order
// of their doors (both sides), out again, on to the corridor's end, and back along the corridor
// to where it began, facing the way it began (then it begins again). In the corridor it looks
// ahead and 0.6 rad to one side (towards the next door, on the way back each side in turn) so
// the corridor's walls are not only seen at grazing angles. In each room it walks
// through the door to the plan's stops; at the last it looks right, then turns left round until
// it faces the door (a full turn), at the others it looks right and left; it walks out facing
// the door. Every move and turn starts and ends at rest, its speed and turn rate rising and
// falling smoothly (continuous acceleration) to at most `speed` (m/s) and `turn_rate` (rad/s), so
// the tour sets its own pace: duration() and length() say how long it is. A hand's sway of a few
// centimetres and degrees rides on it, as on the walk.
class TourPath : public CameraPath {
 public:
  TourPath(const FloorPlan& plan, std::uint64_t seed, double speed, double turn_rate);
  Eigen::Isometry3d pose(double t) const override;
  double duration() const { return duration_; }  // s of one tour
  double length() const { return length_; }      // m walked on the ground, sway aside

 private:
  // One move from a to b while the heading turns from yaw_a to yaw_b, over `seconds`.
  struct Leg {
    Eigen::Vector2d a, b;
    double yaw_a, yaw_b, start, seconds;
  };
  void go(const Eigen::Vector2d& to, double yaw);

  std::vector<Leg> legs_;
  Eigen::Vector2d at_ = Eigen::Vector2d::Zero();
  double yaw_ = 0.0, speed_, turn_rate_, duration_ = 0.0, length_ = 0.0, height_;
  double phase_[8];
};

}  // namespace rgbdmap
