// The map store (MAP.store/): a write adds only the cells whose points changed, the store reads
// back as the last map written, its points file is written anew when old records outweigh the
// current ones, and a damaged store is refused naming the file.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>
#include <tuple>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/map_files/map_store.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

// Points on the floor and walls of a room `x` by `y` m, 1 cm apart on a 2 cm grid, coloured by
// place: cells of 1 m hold a few thousand each.
MapCloud room(float x, float y) {
  MapCloud map;
  const auto add = [&map](float px, float py, float pz) {
    pcl::PointXYZRGB p;
    p.x = px;
    p.y = py;
    p.z = pz;
    p.r = static_cast<std::uint8_t>(px * 40);
    p.g = static_cast<std::uint8_t>(py * 40);
    p.b = static_cast<std::uint8_t>(pz * 80);
    map.push_back(p);
  };
  for (float px = 0.005f; px < x; px += 0.02f)
    for (float py = 0.005f; py < y; py += 0.02f) add(px, py, 0.0f);
  for (float px = 0.005f; px < x; px += 0.02f)
    for (float pz = 0.005f; pz < 2.0f; pz += 0.02f) add(px, 0.0f, pz);
  return map;
}

using Key = std::tuple<float, float, float, std::uint32_t>;
std::vector<Key> sorted(const MapCloud& map) {
  std::vector<Key> keys;
  for (const auto& p : map.points) keys.emplace_back(p.x, p.y, p.z, p.rgba);
  std::sort(keys.begin(), keys.end());
  return keys;
}

std::size_t pointsFiles(const std::string& store) {
  std::size_t n = 0;
  for (const auto& entry : fs::directory_iterator(store))
    n += entry.path().filename().string().rfind("points-", 0) == 0;
  return n;
}

TEST(MapStore, AWriteAddsOnlyTheCellsThatChangedAndReadsBackAsTheLastMap) {
  const std::string store = test::freshDir() + "/map.store";
  MapStore writer(store);
  MapCloud map = room(6.0f, 4.0f);
  MapStore::Written w;
  std::string error;
  ASSERT_TRUE(writer.write(map, w, error)) << error;
  EXPECT_TRUE(w.anew);
  EXPECT_EQ(w.cells, 30u);  // 24 of floor (the wall's lower metre in 6 of them), 6 of wall
  EXPECT_EQ(w.changed, 30u);
  EXPECT_EQ(w.points, map.size());
  const std::uint64_t whole = w.bytes;
  EXPECT_GE(whole, map.size() * 16);
  EXPECT_EQ(sorted(readMapStore(store)), sorted(map));

  // The same points in another order (blocks extracted in another order): nothing to write.
  MapCloud shuffled = map;
  std::shuffle(shuffled.points.begin(), shuffled.points.end(), std::mt19937(3));
  ASSERT_TRUE(writer.write(shuffled, w, error)) << error;
  EXPECT_EQ(w.changed, 0u);
  EXPECT_EQ(w.bytes, 0u);

  // One cell's points move (a loop), one cell's go (pruned), one new cell (seen first now).
  MapCloud next;
  for (auto p : map.points) {
    if (p.x >= 2.0f && p.x < 3.0f && p.y >= 1.0f && p.y < 2.0f && p.z == 0.0f) p.z = 0.004f;
    if (p.x >= 4.0f && p.x < 5.0f && p.y >= 2.0f && p.y < 3.0f && p.z == 0.0f) continue;
    next.push_back(p);
  }
  pcl::PointXYZRGB far;
  far.x = 10.5f;
  far.y = 0.5f;
  far.z = 0.5f;
  next.push_back(far);
  ASSERT_TRUE(writer.write(next, w, error)) << error;
  EXPECT_FALSE(w.anew);
  EXPECT_EQ(w.changed, 2u);  // the moved cell and the new one
  EXPECT_EQ(w.removed, 1u);
  EXPECT_EQ(w.cells, 30u);
  EXPECT_LT(w.bytes, whole / 10) << "a changed cell's points and the index, not the map";
  EXPECT_EQ(sorted(readMapStore(store)), sorted(next));

  // A run started again over the same store replaces it at its first write.
  MapStore again(store);
  ASSERT_TRUE(again.write(map, w, error)) << error;
  EXPECT_TRUE(w.anew);
  EXPECT_EQ(pointsFiles(store), 1u);
  EXPECT_EQ(sorted(readMapStore(store)), sorted(map));
}

// What ROS's ~map_changes sends: the same cells as the store writes, with their coordinates.
TEST(MapChanges, NamesTheCellsThatChangedOrEmptiedAndNothingForTheSamePoints) {
  const MapCloud map = room(3.0f, 2.0f);
  MapChanges changes;
  const MapChanges::Change first = changes.next(MapCells::of(map));
  EXPECT_EQ(first.changed.size(), 9u);  // everything at first: 6 of floor, 3 of the wall's top
  EXPECT_TRUE(first.removed.empty());

  MapCloud shuffled = map;
  std::shuffle(shuffled.points.begin(), shuffled.points.end(), std::mt19937(5));
  const MapChanges::Change same = changes.next(MapCells::of(shuffled));
  EXPECT_TRUE(same.changed.empty() && same.removed.empty());

  // The cell [1, 2) x [0, 1) x [0, 1) loses its points, [2, 3) x [1, 2) x [-1, 0) has one more.
  MapCloud next;
  for (const auto& p : map.points)
    if (!(p.x >= 1.0f && p.x < 2.0f && p.y < 1.0f && p.z < 1.0f)) next.push_back(p);
  pcl::PointXYZRGB below;
  below.x = 2.5f;
  below.y = 1.5f;
  below.z = -0.01f;
  next.push_back(below);
  const MapCells cells = MapCells::of(next);
  const MapChanges::Change change = changes.next(cells);
  ASSERT_EQ(change.changed.size(), 1u);
  EXPECT_EQ(MapCells::coordinatesOf(change.changed[0]), Eigen::Vector3i(2, 1, -1));
  EXPECT_EQ(cells.cells.at(change.changed[0]).points,
            std::vector<std::uint32_t>{static_cast<std::uint32_t>(next.size() - 1)});
  ASSERT_EQ(change.removed.size(), 1u);
  EXPECT_EQ(MapCells::coordinatesOf(change.removed[0]), Eigen::Vector3i(1, 0, 0));

  // Everything again (for a new consumer): every cell, and a cell emptied since still named.
  MapCloud fewer;
  for (const auto& p : next.points)
    if (p.z >= 0.0f) fewer.push_back(p);
  const MapCells fewer_cells = MapCells::of(fewer);
  const MapChanges::Change again = changes.next(fewer_cells, true);
  EXPECT_EQ(again.changed.size(), fewer_cells.cells.size());
  ASSERT_EQ(again.removed.size(), 1u);
  EXPECT_EQ(MapCells::coordinatesOf(again.removed[0]), Eigen::Vector3i(2, 1, -1));

  MapChanges fresh;  // the first call: everything
  EXPECT_EQ(fresh.next(cells).changed.size(), cells.cells.size());
}

TEST(MapStore, ItsPointsAreWrittenAnewWhenOldRecordsOutweighTheMap) {
  const std::string store = test::freshDir() + "/map.store";
  MapStore writer(store);
  MapCloud map = room(10.0f, 8.0f);  // 240 000 points, 3.8 MB
  MapStore::Written w;
  std::string error;
  bool compacted = false;
  std::uint64_t largest = 0;
  // Every cell changes each time (the whole map moved): old records pile up, then go.
  for (int write = 0; write < 12; ++write) {
    for (auto& p : map.points) p.z += 0.001f;
    ASSERT_TRUE(writer.write(map, w, error)) << error;
    compacted = compacted || (write > 0 && w.anew);
    largest = std::max<std::uint64_t>(largest, w.file_bytes);
    EXPECT_EQ(pointsFiles(store), 1u);
  }
  EXPECT_TRUE(compacted);
  EXPECT_LE(largest, 3 * map.size() * 16 + (16u << 20) + map.size() * 16);
  EXPECT_EQ(sorted(readMapStore(store)), sorted(map));
}

// A full disk or a file-size limit mid-write: the write fails naming the file, the store still
// holds the map written before, and the next write, once there is room, is whole again.
TEST(MapStore, AFailedWriteLeavesTheMapWrittenBefore) {
  const std::string store = test::freshDir() + "/map.store";
  MapStore writer(store);
  const MapCloud before = room(4.0f, 3.0f);
  MapStore::Written w;
  std::string error;
  ASSERT_TRUE(writer.write(before, w, error)) << error;
  MapCloud after = room(9.0f, 3.0f);  // a map grown by 5 m: 15 cells more
  for (auto& p : after.points) p.z += 0.002f;

  std::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead
  rlimit limit{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &limit), 0);
  const rlimit small{static_cast<rlim_t>(w.file_bytes + 100000), limit.rlim_max};
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const bool written = writer.write(after, w, error);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limit), 0);
  EXPECT_FALSE(written);
  EXPECT_NE(error.find(store + "/points-1.bin: cannot write: File too large"), std::string::npos)
      << error;
  EXPECT_EQ(sorted(readMapStore(store)), sorted(before));

  ASSERT_TRUE(writer.write(after, w, error)) << error;
  EXPECT_EQ(sorted(readMapStore(store)), sorted(after));
  EXPECT_EQ(w.file_bytes, fs::file_size(store + "/points-1.bin")) << "nothing of the failed write";
}

TEST(MapStore, AMissingTruncatedOrCorruptStoreIsRefusedNamingTheFile) {
  const std::string dir = test::freshDir();
  const auto refusal = [](const std::string& path) -> std::string {
    try {
      readMapStore(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(refusal(dir + "/none.store").find(dir + "/none.store: no map store there"),
            std::string::npos);

  const std::string store = dir + "/map.store";
  MapStore::Written w;
  std::string error;
  ASSERT_TRUE(MapStore(store).write(room(3.0f, 2.0f), w, error)) << error;
  const std::string points = store + "/points-1.bin";
  ASSERT_TRUE(fs::exists(points));
  const auto size = fs::file_size(points);
  fs::resize_file(points, size / 2);
  EXPECT_NE(refusal(store).find(points + ": truncated or corrupt"), std::string::npos)
      << refusal(store);
  {
    std::fstream index(store + "/index.bin", std::ios::in | std::ios::out | std::ios::binary);
    index.seekp(60);
    index.put('\x7f');
  }
  EXPECT_NE(refusal(store).find(store + "/index.bin: corrupt"), std::string::npos)
      << refusal(store);

  // The command names it too, and writes nothing.
  std::string output;
  EXPECT_NE(test::run(test::binary() + " export " + store + " -o " + dir + "/map.pcd", &output), 0);
  EXPECT_NE(output.find(store + "/index.bin"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir + "/map.pcd"));
}

}  // namespace
}  // namespace rgbdmap
