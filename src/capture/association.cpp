#include "rgbdmap/capture/association.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace rgbdmap {

std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& first,
                                                           const std::vector<double>& second,
                                                           double max_difference, double offset) {
  // Candidate pairs. Both lists are sorted in practice, so a sliding window keeps this
  // O(n·w) instead of O(n·m); unsorted input still works, just slower.
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  const bool sorted = std::is_sorted(second.begin(), second.end());
  for (std::size_t i = 0; i < first.size(); ++i) {
    std::size_t begin = 0, end = second.size();
    if (sorted) {
      begin = std::lower_bound(second.begin(), second.end(), first[i] - offset - max_difference) -
              second.begin();
      end = std::upper_bound(second.begin(), second.end(), first[i] - offset + max_difference) -
            second.begin();
    }
    for (std::size_t j = begin; j < end; ++j) {
      const double diff = std::abs(first[i] - (second[j] + offset));
      if (diff < max_difference) candidates.emplace_back(diff, i, j);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> used_first(first.size(), false), used_second(second.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  for (const auto& [diff, i, j] : candidates) {
    if (used_first[i] || used_second[j]) continue;
    used_first[i] = used_second[j] = true;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end(),
            [&](const auto& x, const auto& y) { return first[x.first] < first[y.first]; });
  return matches;
}

}  // namespace rgbdmap
