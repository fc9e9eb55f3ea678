#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace rgbdmap {

// One room off a floor's corridor, as a camera tour visits it.
struct PlanRoom {
  std::string name;
  Eigen::Vector2d min = Eigen::Vector2d::Zero();  // its floor inside the walls (x, y)
  Eigen::Vector2d max = Eigen::Vector2d::Zero();
  // The centre of its door opening on the corridor wall's centre line.
  Eigen::Vector2d door = Eigen::Vector2d::Zero();
  // Where a tour stands to look round the room, from the door inwards (at least one).
  std::vector<Eigen::Vector2d> stops;
};

// What a camera tour needs to know of an office floor: a straight corridor along x, and rooms
// north or south of it, each entered through one door. The walls themselves are the scene's.
struct FloorPlan {
  // The corridor's centre line: a tour begins and ends at `from` and turns round at `to`.
  Eigen::Vector2d corridor_from = Eigen::Vector2d::Zero();
  Eigen::Vector2d corridor_to = Eigen::Vector2d::Zero();
  double camera_height = 1.4;  // m above the floor (z = 0)
  std::vector<PlanRoom> rooms;

  bool empty() const { return rooms.empty() && corridor_from == corridor_to; }
};

}  // namespace rgbdmap
