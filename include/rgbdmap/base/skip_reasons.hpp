#pragma once

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace rgbdmap {

// Frames that could not be used, counted by reason ("colour image: cannot open image"), with the
// full message of the first frame of each reason as an example. Only touched when a frame fails,
// so a mutex costs nothing on the normal path.
class SkipReasons {
 public:
  struct Entry {
    std::string reason;
    std::uint64_t count = 0;
    std::string first;  // the first message of this reason (names the file and line)
  };

  void add(const std::string& reason, const std::string& message);
  // Most frequent first; reasons with equal counts in the order they first occurred.
  std::vector<Entry> entries() const;

 private:
  mutable std::mutex mutex_;
  std::vector<Entry> entries_;  // few distinct reasons: a linear search is fine
};

// "32 frames: colour image: cannot open image (first: rgb.txt:1: rgb/1.png: cannot open
// image)", one line each for the `limit` most frequent reasons, then how many more there are.
std::string describeSkipReasons(const std::vector<SkipReasons::Entry>& entries,
                                std::size_t limit = 3);

}  // namespace rgbdmap
