#pragma once

#include <algorithm>
#include <cstdint>

namespace rgbdmap {

// One voxel of the TSDF (VoxelMap), in memory and on disk (BlockStore).
// 8 bytes: blocks are most of a long run's memory. The distance is kept in steps of 4 um
// (+-13 cm, wider than any band up to 5 m), the weight in steps of 1/2048 of a head-on
// measurement at 1 m, saturating at 32 of them: from there on each measurement moves the
// voxel by a fixed share (an average over the latest few dozen close views, which still lets a
// moved object go), and the 16-bit distance never stops taking it in.
struct TsdfVoxel {
  static constexpr float kSdfStep = 4e-6f;  // m
  static constexpr float kWeightStep = 1.0f / 2048;
  static constexpr float kMaxWeight = 65535 * kWeightStep;

  float sdf() const { return static_cast<float>(sdf_steps) * kSdfStep; }  // metres, truncated
  float weight() const { return static_cast<float>(weight_steps) * kWeightStep; }
  bool observed() const { return weight_steps > 0; }
  // Stores both, rounded; an observed voxel keeps a weight above 0.
  void set(float sdf, float weight) {
    // Rounded by adding 0.5 to a value made positive first: no branch, no call.
    const float s = std::min(std::max(sdf * (1.0f / kSdfStep), -32767.0f), 32767.0f);
    sdf_steps = static_cast<std::int16_t>(static_cast<int>(s + 32768.5f) - 32768);
    const float w = std::min(std::max(weight * (1.0f / kWeightStep) + 0.5f, 1.0f), 65535.0f);
    weight_steps = static_cast<std::uint16_t>(static_cast<int>(w));
  }

  std::int16_t sdf_steps = 0;
  std::uint16_t weight_steps = 0;  // sum of measurement weights; 0 = never observed
  std::uint8_t r = 0, g = 0, b = 0;
  std::uint8_t observations = 0;  // frames fused into this voxel, saturating at 255
};
static_assert(sizeof(TsdfVoxel) == 8, "voxels are 8 bytes");

}  // namespace rgbdmap
