// The mesh (--mesh): marching cubes on exact signed distance fields (a sphere, a plane), where
// it must not put faces (unobserved voxels, a sign jump), and the PLY it is written as.
#include <gtest/gtest.h>
#include <pcl/PolygonMesh.h>
#include <pcl/conversions.h>
#include <pcl/io/ply_io.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <utility>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/map_files/ply_file.hpp"
#include "rgbdmap/mapping/mesh_extractor.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

constexpr float kVoxel = 0.01f;
constexpr float kBand = 0.03f;

// A map whose voxels within `reach` of the surface hold sdf(centre) truncated to the band (all
// voxels of each block touched are set, as fusion leaves them); colour from `colour`.
VoxelMap fieldMap(const std::function<float(const Eigen::Vector3f&)>& sdf,
                  const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                  std::uint32_t min_observations = 1, std::uint8_t observations = 1) {
  VoxelMap map(kVoxel, min_observations);
  map.beginIntegration();
  constexpr int kEdge = VoxelMap::kBlockEdge;
  const Eigen::Vector3i first = (lo / (kVoxel * kEdge)).array().floor().cast<int>();
  const Eigen::Vector3i last = (hi / (kVoxel * kEdge)).array().floor().cast<int>();
  for (int bz = first.z(); bz <= last.z(); ++bz) {
    for (int by = first.y(); by <= last.y(); ++by) {
      for (int bx = first.x(); bx <= last.x(); ++bx) {
        const Eigen::Vector3f centre =
            (Eigen::Vector3f(bx, by, bz) * kEdge + Eigen::Vector3f::Constant(kEdge / 2.0f)) *
            kVoxel;
        if (std::abs(sdf(centre)) > 10 * kVoxel) continue;  // no surface near this block
        VoxelMap::Block& block = map.block(map.touchBlock({bx, by, bz}));
        for (int i = 0; i < VoxelMap::kBlockVoxels; ++i) {
          const Eigen::Vector3i v =
              block.origin + Eigen::Vector3i(i % kEdge, (i / kEdge) % kEdge, i / (kEdge * kEdge));
          const Eigen::Vector3f p = (v.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * kVoxel;
          VoxelMap::Voxel& voxel = block.voxels[i];
          voxel.set(std::clamp(sdf(p), -kBand, kBand), 1.0f);
          voxel.observations = observations;
          voxel.r = voxel.sdf() < 0.0f ? 255 : 0;
          voxel.g = 100;
          voxel.b = 7;
        }
      }
    }
  }
  map.finishIntegration();
  return map;
}

const Eigen::Vector3f kCentre(0.013f, 0.027f, -0.004f);
constexpr float kRadius = 0.2f;

float sphere(const Eigen::Vector3f& p) { return (p - kCentre).norm() - kRadius; }

VoxelMap sphereMap() {
  return fieldMap(sphere, kCentre - Eigen::Vector3f::Constant(0.3f),
                  kCentre + Eigen::Vector3f::Constant(0.3f));
}

TEST(MeshExtractor, SphereIsOnTheSurfaceClosedAndFacesOutwards) {
  const TriangleMesh mesh = extractMesh(sphereMap());
  ASSERT_GT(mesh.triangles.size(), 1000u);
  ASSERT_EQ(mesh.colours.size(), mesh.vertices.size());
  // Linear interpolation of an exact distance: off by the sphere's curvature over a voxel only.
  for (const Eigen::Vector3f& v : mesh.vertices) ASSERT_NEAR(sphere(v), 0.0f, 3e-4f);
  // Watertight: every edge in exactly two triangles, once each way (consistent orientation).
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const TriangleMesh::Triangle& t : mesh.triangles) {
    ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    ASSERT_EQ(count, 1) << edge.first << "-" << edge.second;
    ASSERT_EQ(directed.count({edge.second, edge.first}), 1u) << edge.first << "-" << edge.second;
  }
  // One closed surface of genus 0 (V - E + F = 2), every vertex used.
  const long edges = static_cast<long>(directed.size() / 2);
  EXPECT_EQ(
      static_cast<long>(mesh.vertices.size()) - edges + static_cast<long>(mesh.triangles.size()),
      2);
  // Counter-clockwise seen from outside (the free side): the enclosed volume comes out positive.
  double volume = 0.0;
  for (const TriangleMesh::Triangle& t : mesh.triangles)
    volume += (mesh.vertices[t[0]] - kCentre)
                  .cast<double>()
                  .dot((mesh.vertices[t[1]] - kCentre)
                           .cast<double>()
                           .cross((mesh.vertices[t[2]] - kCentre).cast<double>())) /
              6.0;
  EXPECT_NEAR(volume, 4.0 / 3.0 * M_PI * std::pow(kRadius, 3), 0.01 * volume);
}

TEST(MeshExtractor, PlaneVerticesAndColoursAreInterpolated) {
  constexpr float kHeight = 0.0537f;
  const VoxelMap map = fieldMap([](const Eigen::Vector3f& p) { return p.z() - kHeight; },
                                {-0.2f, -0.2f, -0.1f}, {0.2f, 0.2f, 0.2f});
  const TriangleMesh mesh = extractMesh(map);
  ASSERT_GT(mesh.triangles.size(), 100u);
  // Between the voxel centres at z = 0.045 (sdf -0.0087, red 255) and 0.055 (+0.0013, red 0).
  const float t = 0.0087f / (0.0087f + 0.0013f);
  const auto red = static_cast<int>(std::lround(255.0f * (1.0f - t)));
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    ASSERT_NEAR(mesh.vertices[i].z(), kHeight, 1e-5f);
    ASSERT_EQ(mesh.colours[i][0], red);
    ASSERT_EQ(mesh.colours[i][1], 100);
    ASSERT_EQ(mesh.colours[i][2], 7);
  }
  // Face normals point up, to the positive (observed, free) side.
  for (const TriangleMesh::Triangle& tri : mesh.triangles) {
    const Eigen::Vector3f n = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                  .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
    ASSERT_GT(n.z(), 0.0f);
  }
}

TEST(MeshExtractor, OnlyObservedVoxelsAreMeshed) {
  auto plane = [](const Eigen::Vector3f& p) { return p.z() - 0.0537f; };
  VoxelMap map = fieldMap(plane, {-0.2f, -0.2f, -0.1f}, {0.2f, 0.2f, 0.2f});
  // Forget the voxels over x > 0 (never observed): no face may reach there.
  for (std::uint32_t b = 0; b < map.blockCount(); ++b)
    for (int i = 0; i < VoxelMap::kBlockVoxels; ++i)
      if (map.block(b).origin.x() + i % VoxelMap::kBlockEdge >= 0)
        map.block(b).voxels[i] = VoxelMap::Voxel{};
  const TriangleMesh half = extractMesh(map);
  ASSERT_GT(half.triangles.size(), 100u);
  for (const Eigen::Vector3f& v : half.vertices) ASSERT_LT(v.x(), -0.005f + 1e-6f);

  // Voxels seen fewer times than the map's min_observations are not trusted either.
  EXPECT_TRUE(
      extractMesh(fieldMap(plane, {-0.2f, -0.2f, -0.1f}, {0.2f, 0.2f, 0.2f}, 2, 1)).empty());
  EXPECT_FALSE(
      extractMesh(fieldMap(plane, {-0.2f, -0.2f, -0.1f}, {0.2f, 0.2f, 0.2f}, 2, 2)).empty());
}

TEST(MeshExtractor, NoCurtainWhereTheFieldJumps) {
  // A silhouette: free space in front of the background (+band) next to the inside of a
  // foreground object (-band). The sign changes, but no surface is there.
  auto step = [](const Eigen::Vector3f& p) { return p.x() < 0.0537f ? kBand : -kBand; };
  const VoxelMap map = fieldMap(
      [&](const Eigen::Vector3f& p) { return std::abs(p.x() - 0.0537f) < 0.05f ? step(p) : 1.0f; },
      {-0.1f, -0.1f, -0.1f}, {0.2f, 0.1f, 0.1f});
  EXPECT_TRUE(extractMesh(map).empty());
  // The same with a gradient far steeper than any view gives (5 voxels per voxel).
  const VoxelMap steep = fieldMap([](const Eigen::Vector3f& p) { return 5.0f * (0.0537f - p.x()); },
                                  {-0.1f, -0.1f, -0.1f}, {0.2f, 0.1f, 0.1f});
  EXPECT_TRUE(extractMesh(steep).empty());
  // An oblique view's steeper field (2 voxels per voxel) is still a surface.
  const VoxelMap oblique =
      fieldMap([](const Eigen::Vector3f& p) { return 2.0f * (0.0537f - p.x()); },
               {-0.1f, -0.1f, -0.1f}, {0.2f, 0.1f, 0.1f});
  EXPECT_FALSE(extractMesh(oblique).empty());
}

TEST(PlyFile, RoundTripIsExactAndWritesAreByteIdentical) {
  const std::string dir = test::freshDir();
  const TriangleMesh mesh = extractMesh(sphereMap());
  std::string error;
  ASSERT_TRUE(writePlyAtomically(mesh, dir + "/a.ply", error)) << error;
  ASSERT_TRUE(writePlyAtomically(extractMesh(sphereMap()), dir + "/b.ply", error)) << error;
  EXPECT_EQ(test::readFile(dir + "/a.ply"), test::readFile(dir + "/b.ply"));
  const TriangleMesh loaded = readPly(dir + "/a.ply");
  ASSERT_EQ(loaded.vertices.size(), mesh.vertices.size());
  ASSERT_EQ(loaded.triangles.size(), mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    ASSERT_EQ(loaded.vertices[i], mesh.vertices[i]);
    ASSERT_EQ(loaded.colours[i], mesh.colours[i]);
  }
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    ASSERT_EQ(loaded.triangles[i], mesh.triangles[i]);
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST(PlyFile, AnotherReaderSeesTheSameMesh) {
  // PCL's PLY parser (its own implementation, as MeshLab, Open3D and Blender have theirs) reads
  // the file as a polygon mesh with the same vertices, colours and triangles.
  const std::string dir = test::freshDir();
  const TriangleMesh mesh = extractMesh(sphereMap());
  std::string error;
  ASSERT_TRUE(writePlyAtomically(mesh, dir + "/sphere.ply", error)) << error;
  pcl::PolygonMesh loaded;
  ASSERT_EQ(pcl::io::loadPLYFile(dir + "/sphere.ply", loaded), 0);
  ASSERT_EQ(loaded.polygons.size(), mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    ASSERT_EQ(loaded.polygons[i].vertices.size(), 3u);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(loaded.polygons[i].vertices[k], mesh.triangles[i][k]);
  }
  pcl::PointCloud<pcl::PointXYZRGB> points;
  pcl::fromPCLPointCloud2(loaded.cloud, points);
  ASSERT_EQ(points.size(), mesh.vertices.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(points[i].getVector3fMap(), mesh.vertices[i]);
    ASSERT_EQ(points[i].r, mesh.colours[i][0]);
    ASSERT_EQ(points[i].g, mesh.colours[i][1]);
    ASSERT_EQ(points[i].b, mesh.colours[i][2]);
  }
}

TEST(PlyFile, EmptyMeshIsAValidPly) {
  const std::string dir = test::freshDir();
  std::string error;
  ASSERT_TRUE(writePlyAtomically(TriangleMesh(), dir + "/empty.ply", error)) << error;
  const TriangleMesh loaded = readPly(dir + "/empty.ply");
  EXPECT_TRUE(loaded.vertices.empty());
  EXPECT_TRUE(loaded.triangles.empty());
}

// What readPly says about a file, "" when it reads.
std::string readError(const std::string& path) {
  try {
    readPly(path);
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

TEST(PlyFile, CorruptFilesAreRejectedWithAMessage) {
  const std::string dir = test::freshDir();
  std::string error;
  ASSERT_TRUE(writePlyAtomically(extractMesh(sphereMap()), dir + "/good.ply", error)) << error;
  const std::string good = test::readFile(dir + "/good.ply");
  auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir + "/" + name, std::ios::binary) << bytes;
    return dir + "/" + name;
  };
  const std::string cut = write("cut.ply", good.substr(0, good.size() / 5));
  EXPECT_NE(readError(cut).find(cut + ": truncated: the file ends in vertex"), std::string::npos)
      << readError(cut);
  const std::string cut_faces = write("cut_faces.ply", good.substr(0, good.size() - 5));
  EXPECT_NE(readError(cut_faces).find("truncated: the file ends in face"), std::string::npos)
      << readError(cut_faces);
  EXPECT_NE(readError(write("longer.ply", good + "xyz")).find("3 bytes after the last element"),
            std::string::npos);
  EXPECT_NE(readError(write("text.ply", "hello\n")).find("not a PLY file"), std::string::npos);
  EXPECT_NE(
      readError(write("noend.ply", "ply\nformat binary_little_endian 1.0\n")).find("no end_header"),
      std::string::npos);
  EXPECT_NE(readError(write("ascii.ply", "ply\nformat ascii 1.0\nend_header\n"))
                .find("format ascii is not supported"),
            std::string::npos);
  // A huge vertex count in a small file: refused before anything is allocated.
  const std::string huge =
      write("huge.ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 999999999999\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n" +
                std::string(24, '\0'));
  EXPECT_NE(readError(huge).find("truncated"), std::string::npos) << readError(huge);
  // A face naming a vertex that is not there.
  std::string bad_index =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\nproperty list uchar int "
      "vertex_indices\nend_header\n" +
      std::string(12, '\0') + std::string(1, '\3') + std::string(12, '\0');
  bad_index[bad_index.size() - 4] = 9;
  EXPECT_NE(readError(write("index.ply", bad_index)).find("face 0: vertex index 9 is out of range"),
            std::string::npos)
      << readError(dir + "/index.ply");
  EXPECT_NE(readError(dir + "/missing.ply").find("cannot open"), std::string::npos);
}

TEST(PlyFile, FailedWriteNamesThePathAndKeepsThePreviousMesh) {
  const std::string dir = test::freshDir();
  const std::string path = dir + "/mesh.ply";
  std::string error;
  ASSERT_TRUE(writePlyAtomically(TriangleMesh(), path, error)) << error;
  // A folder in place of the temp file: creating it fails (as root too), with the path named.
  std::filesystem::create_directory(path + ".tmp-" + std::to_string(::getpid()));
  EXPECT_FALSE(writePlyAtomically(extractMesh(sphereMap()), path, error));
  EXPECT_NE(error.find(path + ": cannot create " + path + ".tmp-"), std::string::npos) << error;
  EXPECT_TRUE(readPly(path).vertices.empty());  // still the previous, complete file
  EXPECT_FALSE(writePlyAtomically(TriangleMesh(), dir + "/no/such/folder/mesh.ply", error));
  EXPECT_NE(error.find("No such file or directory"), std::string::npos) << error;
}

}  // namespace
}  // namespace rgbdmap
