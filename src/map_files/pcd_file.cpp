#include "rgbdmap/map_files/pcd_file.hpp"

#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "rgbdmap/base/file_io.hpp"
#include "rgbdmap/map_files/atomic_write.hpp"

namespace rgbdmap {
namespace {

// Binary PCD with fields x y z rgb (16 bytes a point), written with plain write() calls so that
// every failure comes back as an errno (PCL's writer maps the file, where a full disk is a
// SIGBUS).
bool writePcd(const MapCloud& cloud, int fd) {
  const std::string header =
      pcl::PCDWriter::generateHeader<pcl::PointXYZRGB>(cloud, static_cast<int>(cloud.size())) +
      "DATA binary\n";
  if (!writeAll(fd, header.data(), header.size())) return false;
  constexpr std::size_t kPointBytes = 16;
  constexpr std::size_t kChunk = 16384;
  std::vector<char> buffer(kChunk * kPointBytes);
  for (std::size_t first = 0; first < cloud.size(); first += kChunk) {
    const std::size_t count = std::min(kChunk, cloud.size() - first);
    char* out = buffer.data();
    for (std::size_t i = first; i < first + count; ++i, out += kPointBytes) {
      const pcl::PointXYZRGB& p = cloud.points[i];
      std::memcpy(out, &p.x, 4);
      std::memcpy(out + 4, &p.y, 4);
      std::memcpy(out + 8, &p.z, 4);
      std::memcpy(out + 12, &p.rgba, 4);
    }
    if (!writeAll(fd, buffer.data(), count * kPointBytes)) return false;
  }
  return true;
}

}  // namespace

bool writePcdAtomically(const MapCloud& cloud, const std::string& path, std::string& error) {
  return writeFileAtomically(
      path, [&](int fd) { return writePcd(cloud, fd); }, error);
}

}  // namespace rgbdmap
