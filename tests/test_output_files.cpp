// The run's shared rules: output names (what docs/usage.md promises beside MAP.pcd), the
// temporary files a second Ctrl-C removes, pose.source resolution and the exit codes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <stdexcept>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/runtime/exit_code.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/runtime/pose_source.hpp"

namespace rgbdmap {
namespace {

TEST(OutputFiles, StemDropsTheFileNamesExtensionOnly) {
  EXPECT_EQ(stem("map.pcd"), "map");
  EXPECT_EQ(stem("out/room.v2.pcd"), "out/room.v2");
  EXPECT_EQ(stem("out.d/map"), "out.d/map");
  EXPECT_EQ(stem("/tmp/map"), "/tmp/map");
  EXPECT_EQ(stem("out/.pcd"), "out/");
}

TEST(OutputFiles, EverythingIsNamedBesideTheMap) {
  const PipelineOutputs o = outputsBeside("out/room.pcd", "out/room.ply");
  EXPECT_EQ(o.map_path, "out/room.pcd");
  EXPECT_EQ(o.trajectory_path, "out/room_keyframes.txt");
  EXPECT_EQ(o.frame_trajectory_path, "out/room_trajectory.txt");
  EXPECT_EQ(o.config_path, "out/room.yaml");
  EXPECT_EQ(o.mesh_path, "out/room.ply");
  EXPECT_EQ(picturePathOf("out/room.pcd"), "out/room.png");
  EXPECT_EQ(outputsBeside("map.pcd").mesh_path, "");
}

TEST(OutputFiles, TemporaryFilesOfEveryWriter) {
  const std::string pid = std::to_string(::getpid());
  std::vector<std::string> files = temporaryFiles(outputsBeside("out/m.pcd", "out/m.ply"));
  std::sort(files.begin(), files.end());
  const std::vector<std::string> expected = {"out/m.pcd.tmp-" + pid,
                                             "out/m.ply.tmp-" + pid,
                                             "out/m.store/index.bin.tmp-" + pid,
                                             "out/m_keyframes.txt.anchored",
                                             "out/m_keyframes.txt.tmp-" + pid,
                                             "out/m_trajectory.txt.anchored",
                                             "out/m_trajectory.txt.tmp-" + pid};
  EXPECT_EQ(files, expected);
  EXPECT_EQ(temporaryFiles(outputsBeside("m.pcd")).size(), 6u) << "no mesh, no mesh file";
}

TEST(PoseSource, AutoIsTheSourcesGroundTruthElseOdometry) {
  EXPECT_EQ(resolvePoseSource("auto", true, "-"), "groundtruth");
  EXPECT_EQ(resolvePoseSource("auto", false, "-"), "odometry");
  EXPECT_EQ(resolvePoseSource("trajectory", false, "-"), "trajectory");
  EXPECT_EQ(resolvePoseSource("groundtruth", true, "-"), "groundtruth");
  EXPECT_THROW(resolvePoseSource("groundtruth", false, "no ground truth"), InputError);
}

TEST(ExitCode, BadInputIsTwoAnythingElseOne) {
  EXPECT_EQ(runGuarded([] { return 0; }), 0);
  EXPECT_EQ(runGuarded([]() -> int { throw InputError("bad key"); }), 2);
  EXPECT_EQ(runGuarded([]() -> int { throw std::runtime_error("disk"); }), 1);
}

}  // namespace
}  // namespace rgbdmap
