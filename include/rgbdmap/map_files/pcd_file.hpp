#pragma once

#include <string>

#include "rgbdmap/mapping/map_cloud.hpp"

namespace rgbdmap {

// Writes a cloud as binary PCD (fields x y z rgb, 16 bytes a point) atomically
// (atomic_write.hpp). Returns false with `error` naming the path and the system error; the
// destination is left as it was.
bool writePcdAtomically(const MapCloud& cloud, const std::string& path, std::string& error);

}  // namespace rgbdmap
