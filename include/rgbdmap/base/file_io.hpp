#pragma once

#include <cstddef>

namespace rgbdmap {

// Writes all of `size` bytes to `fd`; false with errno set on any failure (a full disk, a quota,
// a file-size limit: SIGXFSZ is ignored, so the limit fails the write with EFBIG).
bool writeAll(int fd, const char* data, std::size_t size);

}  // namespace rgbdmap
