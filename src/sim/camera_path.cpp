#include "rgbdmap/sim/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace rgbdmap {
namespace {

void randomPhases(std::uint64_t seed, double (&phase)[8]) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI);
  for (double& p : phase) p = angle(random);
}

// A hand's sway: a few centimetres and degrees, slow and fast, never repeating exactly.
Eigen::Vector3d sway(double t, const double (&phase)[8]) {
  return Eigen::Vector3d(
      0.03 * std::sin(2.3 * t + phase[0]) + 0.006 * std::sin(7.1 * t + phase[1]),
      0.03 * std::sin(1.9 * t + phase[2]) + 0.006 * std::sin(6.3 * t + phase[3]),
      0.05 * std::sin(0.9 * t + phase[4]) + 0.005 * std::sin(8.3 * t + phase[5]));
}

}  // namespace

Eigen::Isometry3d handheldPose(const Eigen::Vector3d& position, double yaw, double pitch,
                               double roll) {
  const Eigen::Vector3d forward(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                                std::sin(pitch));
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d level_right = forward.cross(up).normalized();
  const Eigen::Vector3d level_down = forward.cross(level_right);
  const Eigen::Vector3d right = std::cos(roll) * level_right + std::sin(roll) * level_down;
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear().col(0) = right;
  pose.linear().col(1) = down;
  pose.linear().col(2) = forward;
  pose.translation() = position;
  return pose;
}

HandheldPath::HandheldPath(const ScenePrimitive& room, std::uint64_t seed, double loop_seconds,
                           double radius)
    : loop_seconds_(loop_seconds) {
  const Eigen::Vector3d size = room.max - room.min;
  center_ = 0.5 * (room.min + room.max);
  center_.z() = room.min.z() + 0.5 * size.z();
  radius_ = radius > 0.0 ? Eigen::Vector2d(radius, radius)
                         : Eigen::Vector2d(0.16 * size.x(), 0.15 * size.y());
  randomPhases(seed, phase_);
}

Eigen::Isometry3d HandheldPath::pose(double t) const {
  const double phi = 2.0 * M_PI * t / loop_seconds_;
  // Slow circle plus a slow sway (a few cm) and a fast tremor (1 cm), as a hand holds a camera.
  const Eigen::Vector3d position =
      center_ +
      Eigen::Vector3d(radius_.x() * std::cos(phi) + 0.05 * std::sin(2.3 * t + phase_[0]) +
                          0.01 * std::sin(7.1 * t + phase_[1]),
                      radius_.y() * std::sin(phi) + 0.05 * std::sin(1.9 * t + phase_[2]) +
                          0.01 * std::sin(6.3 * t + phase_[3]),
                      0.10 * std::sin(0.9 * t + phase_[4]) + 0.008 * std::sin(8.3 * t + phase_[5]));
  // Look outwards, swinging +-17 degrees around the radial direction and 11-25 degrees down,
  // so surfaces are seen from several positions and angles.
  const double yaw = phi + 0.3 * std::sin(2.0 * M_PI * t / 4.1 + phase_[6]);
  const double pitch = -0.32 + 0.12 * std::sin(2.0 * M_PI * t / 3.3 + phase_[7]);
  const double roll = 0.05 * std::sin(1.3 * t + phase_[0] + phase_[3]);
  return handheldPose(position, yaw, pitch, roll);
}

WalkPath::WalkPath(const ScenePrimitive& room, std::uint64_t seed, double loop_seconds,
                   double inset)
    : loop_seconds_(loop_seconds) {
  low_ = room.min.head<2>() + Eigen::Vector2d::Constant(inset);
  high_ = room.max.head<2>() - Eigen::Vector2d::Constant(inset);
  const Eigen::Vector2d size = (high_ - low_).cwiseMax(Eigen::Vector2d::Zero());
  corner_radius_ = std::min(0.6, 0.5 * size.minCoeff());
  height_ = room.min.z() + 0.5 * (room.max.z() - room.min.z());
  lap_length_ = 2.0 * (size.x() + size.y()) - (8.0 - 2.0 * M_PI) * corner_radius_;
  randomPhases(seed, phase_);
}

void WalkPath::along(double s, Eigen::Vector2d& position, double& heading) const {
  const double r = corner_radius_;
  const double straight_x = high_.x() - low_.x() - 2.0 * r;
  const double straight_y = high_.y() - low_.y() - 2.0 * r;
  const double arc = 0.5 * M_PI * r;
  s = std::fmod(s, lap_length_);
  if (s < 0.0) s += lap_length_;
  // From the middle of the near (low y) side, anticlockwise: four sides, each followed by a
  // quarter circle; the first side is walked from its middle, so it comes in two halves.
  s += 0.5 * straight_x;
  const double sides[4] = {straight_x, straight_y, straight_x, straight_y};
  const Eigen::Vector2d starts[4] = {{low_.x() + r, low_.y()},
                                     {high_.x(), low_.y() + r},
                                     {high_.x() - r, high_.y()},
                                     {low_.x(), high_.y() - r}};
  const Eigen::Vector2d centres[4] = {{high_.x() - r, low_.y() + r},
                                      {high_.x() - r, high_.y() - r},
                                      {low_.x() + r, high_.y() - r},
                                      {low_.x() + r, low_.y() + r}};
  for (int side = 0;; side = (side + 1) % 4) {
    const double direction = 0.5 * M_PI * side;
    const Eigen::Vector2d unit(std::cos(direction), std::sin(direction));
    if (s <= sides[side]) {
      position = starts[side] + s * unit;
      heading = direction;
      return;
    }
    s -= sides[side];
    if (s <= arc) {
      const double turned = r > 0.0 ? s / r : 0.0;
      const double from = direction - 0.5 * M_PI;  // the centre-to-camera angle at the arc's start
      position =
          centres[side] + r * Eigen::Vector2d(std::cos(from + turned), std::sin(from + turned));
      heading = direction + turned;
      return;
    }
    s -= arc;
  }
}

Eigen::Isometry3d WalkPath::pose(double t) const {
  Eigen::Vector2d xy;
  double heading = 0.0;
  along(lap_length_ * t / loop_seconds_, xy, heading);
  const Eigen::Vector3d position = Eigen::Vector3d(xy.x(), xy.y(), height_) + sway(t, phase_);
  // Ahead and out: the near wall is on the right of an anticlockwise walk.
  const double yaw = heading - 0.8 + 0.2 * std::sin(2.0 * M_PI * t / 4.3 + phase_[6]);
  const double pitch = -0.25 + 0.1 * std::sin(2.0 * M_PI * t / 3.7 + phase_[7]);
  const double roll = 0.04 * std::sin(1.3 * t + phase_[0] + phase_[3]);
  return handheldPose(position, yaw, pitch, roll);
}

LinePath::LinePath(const ScenePrimitive& room, std::uint64_t seed, double duration, double inset)
    : duration_(duration) {
  const double height = room.min.z() + 0.5 * (room.max.z() - room.min.z());
  start_ = Eigen::Vector3d(room.min.x() + inset, room.min.y() + inset, height);
  end_ = Eigen::Vector3d(room.max.x() - inset, room.min.y() + inset, height);
  randomPhases(seed, phase_);
}

Eigen::Isometry3d LinePath::pose(double t) const {
  const double along = duration_ > 0.0 ? std::clamp(t / duration_, 0.0, 1.0) : 0.0;
  const Eigen::Vector3d position = start_ + along * (end_ - start_) + sway(t, phase_);
  // Filming the wall (towards -y), a little ahead of the walk (+x).
  const double yaw = -0.5 * M_PI + 0.5 + 0.2 * std::sin(2.0 * M_PI * t / 4.3 + phase_[6]);
  const double pitch = -0.25 + 0.1 * std::sin(2.0 * M_PI * t / 3.7 + phase_[7]);
  const double roll = 0.04 * std::sin(1.3 * t + phase_[0] + phase_[3]);
  return handheldPose(position, yaw, pitch, roll);
}

namespace {

// s: how long a ramp from rest to full speed (and back) takes; short enough not to slow the
// tour much, long enough that the camera does not jerk.
constexpr double kRamp = 0.8;

// Fraction [0, 1] of a leg done after t of its `seconds`: speed rises from rest along a
// smoothstep over the ramp, holds, and falls back to rest (continuous speed and acceleration).
double legProgress(double t, double seconds) {
  if (t <= 0.0) return 0.0;
  if (t >= seconds) return 1.0;
  const double ramp = std::min(kRamp, 0.5 * seconds);
  // Distance with a top speed of 1 during a ramp's first s seconds: the smoothstep's integral.
  auto ramped = [ramp](double s) {
    const double u = s / ramp;
    return ramp * (u * u * u - 0.5 * u * u * u * u);
  };
  double done = 0.0;
  if (t < ramp)
    done = ramped(t);
  else if (t <= seconds - ramp)
    done = 0.5 * ramp + (t - ramp);
  else
    done = (seconds - ramp) - ramped(seconds - t);
  return done / (seconds - ramp);
}

// The angle equal to `target` (mod 2 pi) nearest to `from`.
double nearestAngle(double from, double target) {
  return from + std::remainder(target - from, 2.0 * M_PI);
}

}  // namespace

TourPath::TourPath(const FloorPlan& plan, std::uint64_t seed, double speed, double turn_rate)
    : speed_(speed), turn_rate_(turn_rate), height_(plan.camera_height) {
  randomPhases(seed, phase_);
  const Eigen::Vector2d from = plan.corridor_from, to = plan.corridor_to;
  const double direction = to.x() > from.x() ? 1.0 : -1.0;
  const double ahead = direction > 0.0 ? 0.0 : M_PI;
  at_ = from;
  yaw_ = ahead;
  // Rooms in the order the corridor passes their doors.
  std::vector<const PlanRoom*> rooms;
  for (const PlanRoom& room : plan.rooms) rooms.push_back(&room);
  std::stable_sort(rooms.begin(), rooms.end(), [&](const PlanRoom* a, const PlanRoom* b) {
    return direction * a->door.x() < direction * b->door.x();
  });
  // Walking the corridor straight ahead would see its walls only at grazing angles (59 to 78
  // degrees from their normal), where the sensor measures them worst and the map keeps least of
  // them; so the camera looks ahead and to one side, towards the next door on the way out and to
  // each side in turn on the way back.
  const double glance = 0.6;  // rad
  auto looking = [&](double heading, double side) {
    return nearestAngle(yaw_, heading + side * direction * glance);
  };
  for (const PlanRoom* room : rooms) {
    const Eigen::Vector2d outside(room->door.x(), from.y());
    const double side = room->door.y() > from.y() ? 1.0 : -1.0;
    go(outside, looking(ahead, side));
    const double in = nearestAngle(yaw_, side * 0.5 * M_PI);
    go(outside, in);
    // Through the door straight; to a stop off the door's axis only once past the door.
    struct Waypoint {
      Eigen::Vector2d at;
      bool stop;
    };
    std::vector<Waypoint> way;
    if (std::abs(room->stops.front().x() - room->door.x()) > 1e-9)
      way.push_back({room->door + Eigen::Vector2d(0.0, side * 0.6), false});
    for (const Eigen::Vector2d& stop : room->stops) way.push_back({stop, true});
    for (std::size_t k = 0; k + 1 < way.size(); ++k) {
      go(way[k].at, in);
      if (!way[k].stop) continue;
      go(way[k].at, in - 0.5 * M_PI);  // right, left, ahead again
      go(way[k].at, in + 0.5 * M_PI);
      go(way[k].at, in);
    }
    go(way.back().at, in);
    go(way.back().at, in - 0.5 * M_PI);  // right, then left round until facing the door
    go(way.back().at, in + M_PI);
    for (std::size_t k = way.size() - 1; k-- > 0;) go(way[k].at, yaw_);
    go(outside, yaw_);
  }
  go(to, nearestAngle(yaw_, ahead));
  go(to, yaw_ + M_PI);  // turn round at the far end
  // Back in pieces of at most 4 m, looking to either side in turn.
  const double back = ahead + M_PI;
  const int pieces = std::max(1, static_cast<int>(std::ceil((to - from).norm() / 4.0)));
  for (int k = 1; k <= pieces; ++k)
    go(to + (from - to) * k / pieces, looking(back, k % 2 == 1 ? -1.0 : 1.0));
  go(from, nearestAngle(yaw_, ahead));  // and at the start, face the way it began
  if (legs_.empty()) legs_.push_back({from, from, yaw_, yaw_, 0.0, 1.0});
  duration_ = legs_.back().start + legs_.back().seconds;
}

void TourPath::go(const Eigen::Vector2d& to, double yaw) {
  const double distance = (to - at_).norm(), turn = std::abs(yaw - yaw_);
  if (distance < 1e-9 && turn < 1e-9) return;
  // Long enough for the move and the turn each to keep under its top rate (a ramp at each end
  // takes as long as half a ramp at top speed), and at least two ramps.
  const double seconds =
      std::max({distance / speed_ + kRamp, turn / turn_rate_ + kRamp, 2.0 * kRamp});
  const double start = legs_.empty() ? 0.0 : legs_.back().start + legs_.back().seconds;
  legs_.push_back({at_, to, yaw_, yaw, start, seconds});
  length_ += distance;
  at_ = to;
  yaw_ = yaw;
}

Eigen::Isometry3d TourPath::pose(double t) const {
  double local = std::fmod(t, duration_);
  if (local < 0.0) local += duration_;
  auto leg = std::upper_bound(legs_.begin(), legs_.end(), local,
                              [](double value, const Leg& l) { return value < l.start; });
  if (leg != legs_.begin()) --leg;
  const double f = legProgress(local - leg->start, leg->seconds);
  const Eigen::Vector2d xy = leg->a + f * (leg->b - leg->a);
  const double heading = leg->yaw_a + f * (leg->yaw_b - leg->yaw_a);
  const Eigen::Vector3d position = Eigen::Vector3d(xy.x(), xy.y(), height_) + sway(t, phase_);
  const double yaw = heading + 0.15 * std::sin(2.0 * M_PI * t / 4.3 + phase_[6]);
  const double pitch = -0.25 + 0.1 * std::sin(2.0 * M_PI * t / 3.7 + phase_[7]);
  const double roll = 0.04 * std::sin(1.3 * t + phase_[0] + phase_[3]);
  return handheldPose(position, yaw, pitch, roll);
}

}  // namespace rgbdmap
