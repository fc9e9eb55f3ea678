#pragma once

#include <cstddef>
#include <deque>
#include <limits>
#include <utility>
#include <vector>

#include "rgbdmap/capture/association.hpp"

namespace rgbdmap {

// Pairs colour and depth images by stamp as they stream in, with the rule of TUM's associate.py
// (rgbdmap::associate: closest pairs first, within max_difference) applied to a sliding window:
// a pair is handed out once both streams have moved on by more than twice the window, when no
// image still to come could claim either of its images. So a bag gives the same pairs as its
// TUM folder, and a live camera gets the same rule. Not thread-safe: one caller at a time.
template <class Image>
class StampPairer {
 public:
  struct Pair {
    double color_time = 0, depth_time = 0;
    Image color, depth;
  };

  explicit StampPairer(double max_difference = 0.02, std::size_t max_pending = 64)
      : max_difference_(max_difference), max_pending_(max_pending) {}

  void addColor(double time, Image image) { add(color_, time, std::move(image)); }
  void addDepth(double time, Image image) { add(depth_, time, std::move(image)); }

  // The next settled pair, oldest first. With `flush` (the stream ended) every pair the window
  // still holds is settled.
  bool next(Pair& out, bool flush = false) {
    if (color_.empty() || depth_.empty()) return dropSettled(flush), false;
    const double cutoff =
        flush ? std::numeric_limits<double>::infinity()
              : std::min(color_.back().time, depth_.back().time) - 2 * max_difference_;
    const auto matches = associate(times(color_), times(depth_), max_difference_);
    if (!matches.empty()) {
      const auto [i, j] = matches.front();
      if (color_[i].time < cutoff && depth_[j].time < cutoff) {
        unmatched_ += i + j;  // older images that found no partner
        out.color_time = color_[i].time;
        out.depth_time = depth_[j].time;
        out.color = std::move(color_[i].image);
        out.depth = std::move(depth_[j].image);
        color_.erase(color_.begin(), color_.begin() + static_cast<std::ptrdiff_t>(i) + 1);
        depth_.erase(depth_.begin(), depth_.begin() + static_cast<std::ptrdiff_t>(j) + 1);
        return true;
      }
    }
    dropSettled(flush, matches.empty() ? cutoff : std::min(cutoff, firstMatchTime(matches)));
    return false;
  }

  // Images that found no partner (or were pushed out of a full window).
  std::size_t unmatched() const { return unmatched_; }
  std::size_t pending() const { return color_.size() + depth_.size(); }

 private:
  struct Entry {
    double time;
    Image image;
  };

  void add(std::deque<Entry>& list, double time, Image image) {
    list.push_back({time, std::move(image)});
    // One stream alone (the other topic silent) must not hold images without bound.
    if (list.size() > max_pending_) {
      list.pop_front();
      ++unmatched_;
    }
  }
  static std::vector<double> times(const std::deque<Entry>& list) {
    std::vector<double> t;
    t.reserve(list.size());
    for (const Entry& e : list) t.push_back(e.time);
    return t;
  }
  double firstMatchTime(const std::vector<std::pair<std::size_t, std::size_t>>& m) const {
    return std::min(color_[m.front().first].time, depth_[m.front().second].time);
  }
  // Images older than `before` that no pair took can no longer find a partner.
  void dropSettled(bool flush, double before = -std::numeric_limits<double>::infinity()) {
    if (flush) {
      unmatched_ += color_.size() + depth_.size();
      color_.clear();
      depth_.clear();
      return;
    }
    for (auto* list : {&color_, &depth_}) {
      while (!list->empty() && list->front().time < before) {
        list->pop_front();
        ++unmatched_;
      }
    }
  }

  double max_difference_;
  std::size_t max_pending_;
  std::deque<Entry> color_, depth_;
  std::size_t unmatched_ = 0;
};

}  // namespace rgbdmap
