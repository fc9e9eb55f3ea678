// The test suite's own folders: a passing test's freshDir() goes when it ends, a failing test's
// stays to be looked into (the suite writes gigabytes in three builds on CI's disk).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

const std::string kTmp = RGBDMAP_TEST_TMP;

// Run by the test below in a process of their own; disabled, so that CTest never runs them.
TEST(DISABLED_TestDirsChild, Passes) { std::ofstream(test::freshDir() + "/map.pcd") << "map\n"; }
TEST(DISABLED_TestDirsChild, Fails) {
  std::ofstream(test::freshDir() + "/map.pcd") << "map\n";
  ADD_FAILURE() << "failing on purpose: its folder must stay";
}

std::string runChild(const std::string& test, const std::string& environment = "") {
  std::string output;
  test::run(environment + " " + fs::read_symlink("/proc/self/exe").string() +
                " --gtest_also_run_disabled_tests --gtest_filter=DISABLED_TestDirsChild." + test,
            &output);
  return output;
}

TEST(TestDirs, APassingTestsFolderIsRemovedAndAFailingTestsKept) {
  const std::string passed = kTmp + "/DISABLED_TestDirsChild.Passes";
  const std::string failed = kTmp + "/DISABLED_TestDirsChild.Fails";
  fs::remove_all(passed);
  fs::remove_all(failed);

  std::string output = runChild("Passes");
  EXPECT_NE(output.find("[       OK ] DISABLED_TestDirsChild.Passes"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(passed)) << output;

  output = runChild("Fails");
  EXPECT_NE(output.find("[  FAILED  ] DISABLED_TestDirsChild.Fails"), std::string::npos) << output;
  EXPECT_TRUE(fs::exists(failed + "/map.pcd")) << output;

  output = runChild("Passes", "RGBDMAP_TEST_KEEP_DIRS=1");
  EXPECT_TRUE(fs::exists(passed + "/map.pcd")) << "RGBDMAP_TEST_KEEP_DIRS=1 keeps it:\n" << output;
  fs::remove_all(passed);
  fs::remove_all(failed);
}

}  // namespace
}  // namespace rgbdmap
