#include "rgbdmap/tracking/packed_reference.hpp"

#include <cmath>

namespace rgbdmap {
namespace {

constexpr float kMetreSteps = 4096.0f;
constexpr float kGreySteps = 256.0f;

bool packs(float value, float steps, float low, float high, long& out) {
  const float scaled = std::round(value * steps);
  if (!(scaled >= low && scaled <= high)) return false;
  out = static_cast<long>(scaled);
  return true;
}

}  // namespace

PackedReference PackedReference::pack(const AlignmentReference& reference) {
  PackedReference packed;
  packed.valid_pixels = reference.valid_pixels;
  packed.levels.resize(reference.levels.size());
  for (std::size_t l = 0; l < reference.levels.size(); ++l) {
    const AlignmentReference::Level& in = reference.levels[l];
    Level& out = packed.levels[l];
    out.camera = in.camera;
    out.points.reserve(in.points.size());
    for (const Eigen::Vector4f& p : in.points) {
      long x, y, z, i;
      if (!packs(p.x(), kMetreSteps, -32767, 32767, x) ||
          !packs(p.y(), kMetreSteps, -32767, 32767, y) || !packs(p.z(), kMetreSteps, 0, 65535, z) ||
          !packs(p.w(), kGreySteps, 0, 65535, i))
        continue;
      out.points.push_back({static_cast<std::int16_t>(x), static_cast<std::int16_t>(y),
                            static_cast<std::uint16_t>(z), static_cast<std::uint16_t>(i)});
    }
    out.points.shrink_to_fit();
  }
  return packed;
}

void PackedReference::expand(AlignmentReference& out) const {
  out.valid_pixels = valid_pixels;
  out.levels.resize(levels.size());
  for (std::size_t l = 0; l < levels.size(); ++l) {
    AlignmentReference::Level& level = out.levels[l];
    level.camera = levels[l].camera;
    level.points.clear();
    level.points.reserve(levels[l].points.size());
    for (const Point& p : levels[l].points)
      level.points.emplace_back(p.x / kMetreSteps, p.y / kMetreSteps, p.z / kMetreSteps,
                                p.intensity / kGreySteps);
  }
}

std::size_t PackedReference::points() const {
  std::size_t n = 0;
  for (const Level& level : levels) n += level.points.size();
  return n;
}

std::size_t PackedReference::memoryBytes() const {
  return sizeof(PackedReference) + levels.size() * sizeof(Level) + points() * sizeof(Point);
}

}  // namespace rgbdmap
