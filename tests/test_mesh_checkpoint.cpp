// `--mesh` end to end through the real binary: the mesh is written with the final save and with
// every checkpoint (SIGUSR1 here), with and without loop closure, and a mesh that cannot be
// written is reported while the map is still saved.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>

#include "rgbdmap/map_files/ply_file.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using test::kXyz;

TEST(MeshCheckpoint, FinalSaveWritesAMeshThatLoads) {
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --out " + dir +
                          "/map.pcd --mesh " + dir + "/mesh.ply --rate max -q --no-render " +
                          "--stats " + dir + "/stats.json",
                      &output),
            0)
      << output;
  const TriangleMesh mesh = readPly(dir + "/mesh.ply");
  EXPECT_GT(mesh.triangles.size(), 20000u);
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_EQ(test::jsonNumber(stats, "mesh_triangles"), static_cast<double>(mesh.triangles.size()));
  EXPECT_NE(output.find("mesh: " + std::to_string(mesh.triangles.size()) +
                        " triangles written to " + dir + "/mesh.ply"),
            std::string::npos)
      << output;
  EXPECT_NE(stats.find("\"mesh_write\": {\"count\": 1,"), std::string::npos) << stats;
  // The picture of a mesh is drawn as triangles.
  ASSERT_EQ(test::run(test::binary() + " render " + dir + "/mesh.ply", &output), 0) << output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/mesh.png"));
}

TEST(MeshCheckpoint, Sigusr1WritesTheMeshWhileMapping) {
  const std::string dir = test::freshDir();
  test::Process p({test::binary(), "--source", "tum:" + test::tumDir(test::kRpy), "--out",
                   dir + "/map.pcd", "--mesh", dir + "/mesh.ply", "--rate", "0.5", "--no-render",
                   "--set", "checkpoint.every_keyframes=0", "--set", "checkpoint.every_seconds=0"},
                  dir + "/log.txt");
  ASSERT_GT(p.pid(), 0);
  ASSERT_TRUE(test::waitUntil(
      [&] { return test::readFile(dir + "/log.txt").find("poses:") != std::string::npos; }, 60));
  // Ask until a checkpoint's mesh has triangles (the first keyframe may take a while).
  std::size_t asked = 0, seen = 0;
  ASSERT_TRUE(test::waitUntil(
      [&] {
        const std::string log = test::readFile(dir + "/log.txt");
        std::size_t meshes = 0, at = 0;
        while ((at = log.find("mesh: ", at)) != std::string::npos) {
          ++meshes;
          seen = std::stoul(log.substr(at + 6));
          at += 6;
        }
        if (seen > 1000) return true;
        if (meshes == asked) {
          p.signal(SIGUSR1);
          ++asked;
        }
        return false;
      },
      60))
      << test::readFile(dir + "/log.txt");
  const bool still_running = p.running();
  EXPECT_EQ(readPly(dir + "/mesh.ply").triangles.size(), seen);
  EXPECT_TRUE(still_running) << "the checkpoint should come while mapping goes on";
  // Ctrl-C: the final save writes the mesh again (the rest of the frames are not needed here: under
  // ThreadSanitizer they took most of the test's minute).
  const std::size_t meshes = test::countOccurrences(test::readFile(dir + "/log.txt"), "mesh: ");
  p.signal(SIGINT);
  EXPECT_EQ(p.wait(), 0) << test::readFile(dir + "/log.txt");
  EXPECT_GT(test::countOccurrences(test::readFile(dir + "/log.txt"), "mesh: "), meshes);
  EXPECT_GT(readPly(dir + "/mesh.ply").triangles.size(), seen / 2);
}

TEST(MeshCheckpoint, LoopClosureMeshesTheMapThatFollowsTheGraph) {
  // Tracked poses close loops, so keyframes are kept for re-fusion; the mesh is the map's.
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --out " + dir +
                          "/map.pcd --mesh " + dir + "/mesh.ply --rate max -q --no-render " +
                          "--set pose.source=odometry " + "--set keyframe.every_n=2 --stats " +
                          dir + "/stats.json",
                      &output),
            0)
      << output;
  const TriangleMesh mesh = readPly(dir + "/mesh.ply");
  EXPECT_GT(mesh.triangles.size(), 20000u);
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_GT(test::jsonNumber(stats, "kept_keyframes_mb"), 0.1) << stats;
  EXPECT_NE(stats.find("\"loop_closure\": true"), std::string::npos) << stats;
}

TEST(MeshCheckpoint, UnwritableMeshIsReportedAndTheMapStillSaved) {
  const std::string dir = test::freshDir();
  std::filesystem::create_directory(dir + "/mesh.ply");  // a folder where the mesh should go
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --out " + dir +
                          "/map.pcd --mesh " + dir + "/mesh.ply --rate max -q --no-render " +
                          "--set checkpoint.every_keyframes=10 --set checkpoint.min_seconds=0",
                      &output),
            1)
      << output;
  EXPECT_NE(output.find("checkpoint failed, mapping goes on: mesh " + dir + "/mesh.ply: cannot " +
                        "rename into place"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("final map not saved: mesh " + dir + "/mesh.ply"), std::string::npos)
      << output;
  EXPECT_GT(test::loadMap(dir + "/map.pcd").size(), 1000u);
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

}  // namespace
}  // namespace rgbdmap
