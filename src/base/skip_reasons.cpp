#include "rgbdmap/base/skip_reasons.hpp"

#include <algorithm>

namespace rgbdmap {

void SkipReasons::add(const std::string& reason, const std::string& message) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (Entry& e : entries_) {
    if (e.reason == reason) {
      ++e.count;
      return;
    }
  }
  entries_.push_back({reason, 1, message});
}

std::vector<SkipReasons::Entry> SkipReasons::entries() const {
  std::vector<Entry> sorted;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    sorted = entries_;
  }
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const Entry& a, const Entry& b) { return a.count > b.count; });
  return sorted;
}

std::string describeSkipReasons(const std::vector<SkipReasons::Entry>& entries, std::size_t limit) {
  std::string text;
  for (std::size_t i = 0; i < entries.size() && i < limit; ++i) {
    const SkipReasons::Entry& e = entries[i];
    text += "\n  " + std::to_string(e.count) + (e.count == 1 ? " frame: " : " frames: ") + e.reason;
    if (!e.first.empty()) text += " (first: " + e.first + ")";
  }
  if (entries.size() > limit)
    text += "\n  and " + std::to_string(entries.size() - limit) + " more reasons";
  return text;
}

}  // namespace rgbdmap
