// Atomic map writes: a killed writer never leaves a partial file at the destination, and a
// failed write is reported without touching what is there. (Forks, so not run under TSan.)
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <thread>

#include "rgbdmap/map_files/pcd_file.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

// A child process writes a large map over and over and is killed at random moments: the
// destination must always be absent or a complete map, never a partial file.
TEST(AtomicWrite, KilledWriterNeverLeavesPartialFile) {
  const std::string dir = test::freshDir();
  const std::string path = dir + "/map.pcd";
  MapCloud cloud;
  cloud.resize(1500000);
  for (std::size_t i = 0; i < cloud.size(); ++i) cloud[i].x = static_cast<float>(i);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> delay_ms(1, 120);
  int complete_seen = 0;
  for (int round = 0; round < 12; ++round) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      std::string error;
      for (;;)
        if (!writePcdAtomically(cloud, path, error)) ::_exit(3);
    }
    if (round == 0) {
      // Once a complete map is in place (a busy machine may take seconds to write one), every
      // later kill must leave it or a newer complete one.
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
      while (!fs::exists(path) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng) * (round + 1) / 2));
    }
    ::kill(child, round % 2 ? SIGKILL : SIGTERM);
    int status = 0;
    ::waitpid(child, &status, 0);
    if (fs::exists(path)) {
      MapCloud loaded;
      ASSERT_EQ(pcl::io::loadPCDFile(path, loaded), 0) << "round " << round;
      ASSERT_EQ(loaded.size(), cloud.size()) << "round " << round;
      ++complete_seen;
    }
    for (const auto& entry : fs::directory_iterator(dir))
      if (entry.path() != path) fs::remove(entry.path());  // the killed writer's temp file
  }
  EXPECT_EQ(complete_seen, 12);
}

TEST(AtomicWrite, DiskFullKeepsThePreviousMap) {
  const std::string dir = test::freshDir();
  const std::string path = dir + "/map.pcd";
  MapCloud small;
  small.resize(10);
  std::string error;
  ASSERT_TRUE(writePcdAtomically(small, path, error)) << error;
  // A child with a 64 KB file size limit plays "disk full" for a 1 MB map (works as root too).
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{64 * 1024, 64 * 1024};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    MapCloud big;
    big.resize(100000);
    std::string message;
    const bool ok = writePcdAtomically(big, path, message);
    const bool names_file = message.find(path) != std::string::npos;
    ::_exit(ok ? 1 : (names_file ? 0 : 2));
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0)
      << "1: the write claimed success, 2: the error did not name the file";
  EXPECT_EQ(test::loadMap(path).size(), 10u);
  for (const auto& entry : fs::directory_iterator(dir)) EXPECT_EQ(entry.path(), path);
}

TEST(AtomicWrite, WrittenMapLoadsBackExactly) {
  const std::string dir = test::freshDir();
  MapCloud cloud;
  cloud.resize(40000);  // more than one write chunk
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].x = static_cast<float>(i) * 0.25f;
    cloud[i].y = -static_cast<float>(i) / 3.0f;
    cloud[i].z = 1.0f + static_cast<float>(i % 97);
    cloud[i].r = static_cast<std::uint8_t>(i);
    cloud[i].g = static_cast<std::uint8_t>(i / 7);
    cloud[i].b = static_cast<std::uint8_t>(255 - i % 256);
  }
  std::string error;
  ASSERT_TRUE(writePcdAtomically(cloud, dir + "/map.pcd", error)) << error;
  const MapCloud loaded = test::loadMap(dir + "/map.pcd");
  ASSERT_EQ(loaded.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(loaded[i].getVector3fMap(), cloud[i].getVector3fMap()) << i;
    ASSERT_EQ(loaded[i].rgba & 0xffffffu, cloud[i].rgba & 0xffffffu) << i;
  }
}

// A file-size limit hit mid-run (the same error path as a full disk or a quota): the process is
// not killed by SIGXFSZ; each failed checkpoint is reported naming the path and the error and
// mapping goes on; the failed final save exits 1 saying where the last good map is, and that map
// loads.
TEST(AtomicWrite, FileSizeLimitMidRunIsReportedAndTheLastCheckpointLoads) {
  const std::string dir = test::freshDir();
  const std::string path = dir + "/map.pcd";
  std::string output;
  // 2 MB (4096 blocks of 512 bytes): the first checkpoints (under ~125,000 points) fit, the
  // full map (~330,000 points, 5 MB) does not.
  const int code = test::run("ulimit -f 4096 && exec " + test::binary() +
                                 " --source tum:" + test::tumDir(test::kRpy) + " --out " + path +
                                 " --rate max -q --no-render --set checkpoint.every_keyframes=1"
                                 " --set checkpoint.min_seconds=0 --set checkpoint.store=false",
                             &output);
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("checkpoint failed, mapping goes on: " + path + ": cannot write " + path +
                        ".tmp-"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("File too large (EFBIG"), std::string::npos) << output;
  const std::string final_failed = "final map not saved: " + path + ": cannot write ";
  const std::size_t at = output.find(final_failed);
  ASSERT_NE(at, std::string::npos) << output;
  const std::string good = "; the last good map (";
  const std::size_t good_at = output.find(good, at);
  ASSERT_NE(good_at, std::string::npos) << output;
  const std::size_t points = std::stoul(output.substr(good_at + good.size()));
  EXPECT_NE(output.find(" points) is still complete at " + path, good_at), std::string::npos);
  const MapCloud last = test::loadMap(path);
  EXPECT_EQ(last.size(), points);
  EXPECT_GT(last.size(), 10000u);
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST(AtomicWrite, EmptyMapIsAValidPcd) {
  const std::string dir = test::freshDir();
  std::string error;
  ASSERT_TRUE(writePcdAtomically(MapCloud(), dir + "/empty.pcd", error)) << error;
  // Read as a generic cloud: PCL's typed loader trips UBSan on zero points (&data[0] of an
  // empty vector in its header-only conversion), which is PCL's problem, not the file's.
  pcl::PCLPointCloud2 loaded;
  ASSERT_EQ(pcl::io::loadPCDFile(dir + "/empty.pcd", loaded), 0);
  EXPECT_EQ(loaded.width * loaded.height, 0u);
  std::string fields;
  for (const auto& f : loaded.fields) fields += f.name + " ";
  EXPECT_EQ(fields, "x y z rgb ");
}

}  // namespace
}  // namespace rgbdmap
