// The mesh of the synthetic room (issue 16): every frame fused, points sampled on the mesh's
// triangles score F@1cm >= 0.98 against the exact geometry, with the same scoring as the maps.
#include <gtest/gtest.h>

#include <chrono>
#include <iostream>
#include <random>

#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/map_files/ply_file.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

// Points on the triangles, about `per_m2` a square metre, each triangle getting a share by its
// area (fixed seed: the same mesh gives the same points).
pcl::PointCloud<pcl::PointXYZRGB> samplePoints(const TriangleMesh& mesh, double per_m2) {
  std::vector<double> cumulative;
  cumulative.reserve(mesh.triangles.size());
  double area = 0.0;
  for (const TriangleMesh::Triangle& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    area += 0.5 * (mesh.vertices[t[1]].cast<double>() - a)
                      .cross(mesh.vertices[t[2]].cast<double>() - a)
                      .norm();
    cumulative.push_back(area);
  }
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  if (mesh.triangles.empty()) return cloud;
  const auto count = static_cast<std::size_t>(area * per_m2);
  std::mt19937_64 random(16);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  cloud.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const auto at = std::lower_bound(cumulative.begin(), cumulative.end(), uniform(random) * area);
    const TriangleMesh::Triangle& t =
        mesh.triangles[std::min<std::size_t>(at - cumulative.begin(), mesh.triangles.size() - 1)];
    double u = uniform(random), v = uniform(random);
    if (u + v > 1.0) {  // folded back into the triangle: uniform over its area
      u = 1.0 - u;
      v = 1.0 - v;
    }
    const Eigen::Vector3f a = mesh.vertices[t[0]];
    cloud[i].getVector3fMap() = a + static_cast<float>(u) * (mesh.vertices[t[1]] - a) +
                                static_cast<float>(v) * (mesh.vertices[t[2]] - a);
  }
  return cloud;
}

TEST(MeshRoom, SampledMeshScoresAgainstTheExactRoom) {
  const std::string room =
      test::sharedSynthetic("room_6x5x3_90_frames", " --room 6x5x3 --fps 10 --frames 90");
  const std::string dir = test::freshDir();
  std::string output;
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + room + " --out " + dir +
                          "/map.pcd --mesh " + dir +
                          "/mesh.ply --rate max --set keyframe.every_n=1 --set "
                          "filter.max_depth=5 -q --no-render --stats " +
                          dir + "/stats.json",
                      &output),
            0)
      << output;
  std::cout << "mapping with --mesh: "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
            << " s\n";
  const TriangleMesh mesh = readPly(dir + "/mesh.ply");
  const SyntheticGroundTruth truth = loadSyntheticGroundTruth(room);
  // 4 points a cm^2: every reference sample has some within 1 cm unless the mesh has a hole.
  const pcl::PointCloud<pcl::PointXYZRGB> points = samplePoints(mesh, 40000.0);
  const MapScore score = evaluateMap(points, truth.scene, truth.visible_surface, 0.01);
  const MapScore vertices =
      evaluateMap(test::loadMap(dir + "/map.pcd"), truth.scene, truth.visible_surface, 0.01);
  std::cout << "mesh: " << mesh.vertices.size() << " vertices, " << mesh.triangles.size()
            << " triangles, " << points.size() << " samples: " << score.toJson()
            << "point map: " << vertices.toJson();
  ::testing::Test::RecordProperty("mesh_f_score", std::to_string(score.f_score));
  ::testing::Test::RecordProperty("mesh_precision", std::to_string(score.precision));
  ::testing::Test::RecordProperty("mesh_recall", std::to_string(score.recall));
  EXPECT_GE(score.f_score, 0.98);
  EXPECT_GE(score.precision, 0.98);
  EXPECT_LT(score.mean_distance, 0.002);
  // The mesh covers nearly what the point map covers (measured 0.986 vs 0.994: cells at the
  // edge of what was seen lack an observed corner).
  EXPECT_GE(score.recall, vertices.recall - 0.015);
  EXPECT_EQ(test::jsonNumber(test::readFile(dir + "/stats.json"), "mesh_triangles"),
            static_cast<double>(mesh.triangles.size()));
}

}  // namespace
}  // namespace rgbdmap
