#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rgbdmap {

// A scratch file that byte strings are appended to and read back from: where the kept keyframes'
// images (KeyframeStore) and the map's blocks (BlockStore) go when they no longer fit in memory,
// `what` naming them in its messages. It lies in the system's temporary
// folder (TMPDIR, else /tmp) and is unlinked as soon as it is made, so that no run, however it
// ends, leaves one behind; the space is the system's again when the run exits.
class SpillFile {
 public:
  explicit SpillFile(std::string what = "keyframe images") : what_(std::move(what)) {}
  ~SpillFile();
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;

  // Appends `a` then `b`; returns where `a` begins (b follows it). False, with `error` naming
  // the folder and what went wrong, when the file cannot be made or written (the disk full).
  bool append(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b,
              std::uint64_t& offset, std::string& error);
  // Reads `size` bytes at `offset` into `out`; false, with `error`, when that fails. Any thread
  // may read what was appended before it got the offset (a session written on its own thread).
  bool read(std::uint64_t offset, std::size_t size, std::vector<std::uint8_t>& out,
            std::string& error) const;
  // Bytes written so far.
  std::uint64_t bytes() const { return end_.load(); }

 private:
  bool open(std::string& error);

  std::string what_;
  int fd_ = -1;
  std::string folder_;
  std::atomic<std::uint64_t> end_{0};
};

}  // namespace rgbdmap
