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

#include "rgbdmap/runtime/checkpoint_writer.hpp"
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
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng) * (round + 1) / 2));
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
  EXPECT_GT(complete_seen, 0);
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
