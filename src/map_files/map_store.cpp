#include "rgbdmap/map_files/map_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "rgbdmap/base/binary_record.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_io.hpp"
#include "rgbdmap/map_files/atomic_write.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

constexpr const char* kIndexFile = "index.bin";
constexpr char kIndexKind[5] = "MIDX";
constexpr std::uint32_t kVersion = 1;
constexpr std::uint64_t kPointBytes = 16;   // x y z rgba, as a PCD's
constexpr std::uint64_t kHeaderBytes = 16;  // a record's cell key and point count

void packPoint(const pcl::PointXYZRGB& p, char* out) {
  std::memcpy(out, &p.x, 4);
  std::memcpy(out + 4, &p.y, 4);
  std::memcpy(out + 8, &p.z, 4);
  std::memcpy(out + 12, &p.rgba, 4);
}

std::uint64_t recordBytes(std::uint64_t points) { return kHeaderBytes + points * kPointBytes; }

// Appends the cells' records to `fd` from `offset` on, noting where each starts.
bool appendRecords(int fd, const MapCloud& map,
                   const std::unordered_map<std::uint64_t, MapCells::Cell>& cells,
                   const std::vector<std::uint64_t>& keys, std::uint64_t offset,
                   std::unordered_map<std::uint64_t, std::uint64_t>& offsets) {
  std::vector<char> buffer;
  for (const std::uint64_t key : keys) {
    const MapCells::Cell& cell = cells.at(key);
    const std::uint64_t count = cell.points.size();
    buffer.resize(recordBytes(count));
    std::memcpy(buffer.data(), &key, 8);
    std::memcpy(buffer.data() + 8, &count, 8);
    char* out = buffer.data() + kHeaderBytes;
    for (const std::uint32_t i : cell.points) {
      packPoint(map.points[i], out);
      out += kPointBytes;
    }
    if (!writeAll(fd, buffer.data(), buffer.size())) return false;
    offsets[key] = offset;
    offset += buffer.size();
  }
  return ::fdatasync(fd) == 0;
}

}  // namespace

MapStore::MapStore(std::string path) : path_(std::move(path)) {}

std::string MapStore::pointsFile(std::uint64_t generation) const {
  return path_ + "/points-" + std::to_string(generation) + ".bin";
}

bool MapStore::write(const MapCloud& map, Written& written, std::string& error) {
  written = {};
  const MapCells grouped = MapCells::of(map);
  const std::unordered_map<std::uint64_t, MapCells::Cell>& cells = grouped.cells;
  written.points = map.size();
  written.cells = cells.size();
  std::vector<std::uint64_t> changed;
  std::uint64_t live_bytes = 0, changed_bytes = 0;
  for (const auto& [key, cell] : cells) {
    live_bytes += recordBytes(cell.points.size());
    const auto before = cells_.find(key);
    if (before != cells_.end() && before->second.hash == cell.hash &&
        before->second.count == cell.points.size())
      continue;
    changed.push_back(key);
    changed_bytes += recordBytes(cell.points.size());
  }
  for (const auto& [key, cell] : cells_) written.removed += cells.count(key) == 0 ? 1 : 0;
  written.changed = changed.size();
  if (changed.empty() && written.removed == 0 && generation_ > 0) {
    written.file_bytes = file_bytes_;
    return true;  // the index on disk names this map already
  }

  // Whole: the first write of the run, or when the file would hold more old records than
  // current ones (and more than a few MB of them).
  const bool anew = generation_ == 0 || file_bytes_ + changed_bytes > 2 * live_bytes + (16u << 20);
  std::uint64_t generation = generation_;
  std::error_code ec;
  if (anew) {
    fs::create_directories(path_, ec);
    if (ec) {
      error = path_ + ": cannot create the map store: " + ec.message();
      return false;
    }
    // Past every points file there (an earlier run's index may still name one).
    for (const auto& entry : fs::directory_iterator(path_, ec)) {
      const std::string name = entry.path().filename().string();
      std::uint64_t g = 0;
      if (std::sscanf(name.c_str(), "points-%lu.bin", &g) == 1)
        generation = std::max(generation, g);
    }
    ++generation;
    changed.clear();
    for (const auto& [key, cell] : cells) changed.push_back(key);
  }
  std::sort(changed.begin(), changed.end());

  const std::string points_path = pointsFile(generation);
  const int fd =
      ::open(points_path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | (anew ? O_TRUNC : 0), 0644);
  const std::uint64_t start = anew ? 0 : file_bytes_;
  std::unordered_map<std::uint64_t, std::uint64_t> offsets;
  bool ok = fd >= 0 && ::lseek(fd, static_cast<off_t>(start), SEEK_SET) >= 0 &&
            appendRecords(fd, map, cells, changed, start, offsets);
  if (!ok) error = points_path + ": cannot write: " + std::strerror(errno);
  std::uint64_t end = start;
  for (const std::uint64_t key : changed) end += recordBytes(cells.at(key).points.size());

  // The index of the new map, cells in key order.
  std::vector<std::uint64_t> keys;
  keys.reserve(cells.size());
  for (const auto& [key, cell] : cells) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  std::string index_error;
  ok = ok &&
       writeFileAtomically(
           path_ + "/" + kIndexFile,
           [&](int index_fd) {
             RecordWriter out(index_fd, kIndexKind, kVersion);
             out.put<std::uint64_t>(generation);
             out.put<double>(kCellSize);
             out.put<std::uint64_t>(map.size());
             out.put<std::uint64_t>(keys.size());
             for (const std::uint64_t key : keys) {
               const auto at = offsets.find(key);
               out.put<std::uint64_t>(key);
               out.put<std::uint64_t>(at != offsets.end() ? at->second : cells_.at(key).offset);
               out.put<std::uint64_t>(cells.at(key).points.size());
             }
             return out.finish();
           },
           index_error);
  if (!ok && error.empty()) error = index_error;
  if (!ok) {
    // The index on disk still names the last map: drop what was added for this one.
    if (fd >= 0 && anew) ::unlink(points_path.c_str());
    if (fd >= 0 && !anew && ::ftruncate(fd, static_cast<off_t>(file_bytes_)) != 0) {
      // Left as it is: the index names none of it.
    }
    if (fd >= 0) ::close(fd);
    return false;
  }
  ::close(fd);

  std::unordered_map<std::uint64_t, Cell> now;
  now.reserve(cells.size());
  for (const auto& [key, cell] : cells) {
    const auto at = offsets.find(key);
    now[key] = {cell.hash, at != offsets.end() ? at->second : cells_.at(key).offset,
                cell.points.size()};
  }
  cells_ = std::move(now);
  if (anew) {
    // The index names the new file only: every other points file goes.
    for (const auto& entry : fs::directory_iterator(path_, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("points-", 0) == 0 && entry.path().string() != points_path)
        fs::remove(entry.path(), ec);
    }
  }
  generation_ = generation;
  file_bytes_ = end;
  written.anew = anew;
  const std::uintmax_t index_bytes = fs::file_size(path_ + "/" + kIndexFile, ec);
  written.bytes = (end - start) + (ec ? 0 : index_bytes);
  written.file_bytes = file_bytes_;
  return true;
}

MapCloud readMapStore(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec))
    throw InputError(path +
                     ": no map store there (a run writes it beside its map as MAP.store, "
                     "docs/usage.md#the-map-store)");
  BinaryReader index = openRecord(path + "/" + kIndexFile, kIndexKind, kVersion);
  const std::uint64_t generation = index.get<std::uint64_t>();
  if (index.get<double>() != MapStore::kCellSize)
    index.fail("cells of another size than this rgbdmap's");
  const std::uint64_t total = index.get<std::uint64_t>();
  const std::size_t cells = index.count(24);
  const std::string points_path = path + "/points-" + std::to_string(generation) + ".bin";
  std::ifstream points(points_path, std::ios::binary);
  if (!points)
    throw InputError(points_path + ": cannot open (" + std::strerror(errno) +
                     "), which the store's index names");
  const std::uint64_t file_bytes = fs::file_size(points_path, ec);
  MapCloud map;
  map.reserve(total);
  std::vector<char> buffer;
  for (std::size_t c = 0; c < cells; ++c) {
    const auto key = index.get<std::uint64_t>();
    const auto offset = index.get<std::uint64_t>();
    const auto count = index.get<std::uint64_t>();
    std::uint64_t header[2] = {0, 0};
    if (count > file_bytes / kPointBytes || offset + recordBytes(count) > file_bytes ||
        !points.seekg(static_cast<std::streamoff>(offset)) ||
        !points.read(reinterpret_cast<char*>(header), sizeof header) || header[0] != key ||
        header[1] != count)
      throw InputError(points_path + ": truncated or corrupt (the record of cell " +
                       std::to_string(c) + " at byte " + std::to_string(offset) +
                       " is not what the index names)");
    buffer.resize(count * kPointBytes);
    points.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    for (std::uint64_t i = 0; i < count; ++i) {
      pcl::PointXYZRGB p;
      std::memcpy(&p.x, buffer.data() + i * kPointBytes, 4);
      std::memcpy(&p.y, buffer.data() + i * kPointBytes + 4, 4);
      std::memcpy(&p.z, buffer.data() + i * kPointBytes + 8, 4);
      std::memcpy(&p.rgba, buffer.data() + i * kPointBytes + 12, 4);
      map.push_back(p);
    }
  }
  if (!index.atEnd()) index.fail("corrupt (bytes after the cells)");
  if (map.size() != total)
    index.fail("corrupt (" + std::to_string(map.size()) + " points in its cells, " +
               std::to_string(total) + " in its total)");
  map.width = static_cast<std::uint32_t>(map.size());
  map.height = 1;
  map.is_dense = true;
  return map;
}

}  // namespace rgbdmap
