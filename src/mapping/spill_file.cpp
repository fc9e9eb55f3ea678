#include "rgbdmap/mapping/spill_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace rgbdmap {
namespace {

// Writes or reads all of `size` bytes at `offset` (the calls may do part of it at a time).
template <typename Call, typename Buffer>
bool whole(Call call, int fd, Buffer data, std::size_t size, std::uint64_t offset) {
  while (size > 0) {
    const ssize_t done = call(fd, data, size, static_cast<off_t>(offset));
    if (done < 0 && errno == EINTR) continue;
    if (done <= 0) {
      if (done == 0) errno = EIO;  // a read past the end: the file is not what was written
      return false;
    }
    data += done;
    size -= static_cast<std::size_t>(done);
    offset += static_cast<std::uint64_t>(done);
  }
  return true;
}

}  // namespace

SpillFile::~SpillFile() {
  if (fd_ >= 0) ::close(fd_);
}

bool SpillFile::open(std::string& error) {
  const char* tmpdir = std::getenv("TMPDIR");
  folder_ = tmpdir && *tmpdir ? tmpdir : "/tmp";
  std::string name = folder_ + "/rgbdmap-scratch-XXXXXX";
  fd_ = ::mkstemp(name.data());
  if (fd_ < 0) {
    error = folder_ + ": cannot make a file for " + what_ + ": " + std::strerror(errno);
    return false;
  }
  ::unlink(name.c_str());  // gone with the last descriptor, however the run ends
  return true;
}

bool SpillFile::append(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b,
                       std::uint64_t& offset, std::string& error) {
  if (fd_ < 0 && !open(error)) return false;
  const std::uint64_t end = end_.load();
  if (!whole(::pwrite, fd_, a.data(), a.size(), end) ||
      !whole(::pwrite, fd_, b.data(), b.size(), end + a.size())) {
    error = folder_ + ": cannot write " + what_ + ": " + std::strerror(errno);
    return false;
  }
  offset = end;
  end_.store(end + a.size() + b.size());
  return true;
}

bool SpillFile::read(std::uint64_t offset, std::size_t size, std::vector<std::uint8_t>& out,
                     std::string& error) const {
  out.resize(size);
  const bool written = fd_ >= 0 && offset + size <= end_.load();
  if (!written || !whole(::pread, fd_, out.data(), size, offset)) {
    error = folder_ + ": cannot read " + what_ +
            " back: " + (!written ? "not written" : std::strerror(errno));
    return false;
  }
  return true;
}

}  // namespace rgbdmap
