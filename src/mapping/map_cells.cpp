#include "rgbdmap/mapping/map_cells.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rgbdmap {
namespace {

constexpr double kHalf = 1 << 20;  // cells each side of 0

std::uint64_t mix(std::uint64_t x) {  // splitmix64's finaliser
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

std::uint64_t MapCells::keyOf(const pcl::PointXYZRGB& p) {
  const auto axis = [](float v) {
    const double cell = std::floor(static_cast<double>(v) / kCellSize);
    const double clamped = std::isfinite(cell) ? std::clamp(cell, -kHalf, kHalf - 1) : 0.0;
    return static_cast<std::uint64_t>(clamped + kHalf);
  };
  return axis(p.x) << 42 | axis(p.y) << 21 | axis(p.z);
}

Eigen::Vector3i MapCells::coordinatesOf(std::uint64_t key) {
  constexpr std::uint64_t kMask = (1u << 21) - 1;
  const auto axis = [](std::uint64_t bits) {
    return static_cast<int>(static_cast<std::int64_t>(bits) - static_cast<std::int64_t>(kHalf));
  };
  return {axis(key >> 42 & kMask), axis(key >> 21 & kMask), axis(key & kMask)};
}

MapCells MapCells::of(const MapCloud& map) {
  MapCells out;
  Cell* last = nullptr;  // neighbouring points mostly share a cell
  std::uint64_t last_key = 0;
  for (std::uint32_t i = 0; i < map.size(); ++i) {
    const pcl::PointXYZRGB& p = map.points[i];
    const std::uint64_t key = keyOf(p);
    if (last == nullptr || key != last_key) {
      last = &out.cells[key];
      last_key = key;
    }
    // The point as a PCD holds it (x y z rgba), hashed so that a sum ignores the order.
    std::uint32_t words[4];
    std::memcpy(&words[0], &p.x, 4);
    std::memcpy(&words[1], &p.y, 4);
    std::memcpy(&words[2], &p.z, 4);
    std::memcpy(&words[3], &p.rgba, 4);
    const std::uint64_t a = std::uint64_t{words[1]} << 32 | words[0];
    const std::uint64_t b = std::uint64_t{words[3]} << 32 | words[2];
    last->hash += mix(a ^ mix(b));
    last->points.push_back(i);
  }
  return out;
}

MapChanges::Change MapChanges::next(const MapCells& now, bool everything) {
  Change change;
  std::unordered_map<std::uint64_t, Seen> seen;
  seen.reserve(now.cells.size());
  for (const auto& [key, cell] : now.cells) {
    seen[key] = {cell.hash, cell.points.size()};
    const auto before = last_.find(key);
    if (everything || before == last_.end() || before->second.hash != cell.hash ||
        before->second.count != cell.points.size())
      change.changed.push_back(key);
  }
  for (const auto& [key, cell] : last_)
    if (!now.cells.count(key)) change.removed.push_back(key);
  std::sort(change.changed.begin(), change.changed.end());
  std::sort(change.removed.begin(), change.removed.end());
  last_ = std::move(seen);
  return change;
}

}  // namespace rgbdmap
