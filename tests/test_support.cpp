#include "test_support.hpp"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>

namespace rgbdmap::test {

std::string dataDir() { return RGBDMAP_DATA_DIR; }
std::string tumDir(const std::string& name) { return dataDir() + "/tum/" + name; }
std::string binary() { return RGBDMAP_BINARY; }

std::string freshDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string dir = std::string(RGBDMAP_TEST_TMP) + "/" + info->test_suite_name() + "." +
                          info->name();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

int run(const std::string& command, std::string* output) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buffer{};
  std::string text;
  while (std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) text.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  if (output) *output = text;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

MapCloud loadMap(const std::string& path) {
  MapCloud cloud;
  EXPECT_EQ(pcl::io::loadPCDFile(path, cloud), 0) << path;
  return cloud;
}

}  // namespace rgbdmap::test
