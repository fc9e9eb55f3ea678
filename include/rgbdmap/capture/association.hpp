#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace rgbdmap {

// TUM's associate.py: every pair (a, b) with |a - (b + offset)| < max_difference, sorted by
// that difference, accepted greedily when neither stamp is taken yet, returned sorted by a.
// Returns index pairs (into `first`, into `second`).
std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& first,
                                                           const std::vector<double>& second,
                                                           double max_difference = 0.02,
                                                           double offset = 0.0);

}  // namespace rgbdmap
