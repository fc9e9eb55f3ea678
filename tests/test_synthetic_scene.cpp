// The synthetic scene's exact geometry and the sequences rendered from it: ray hits and
// distances checked by hand, the YAML round trip, and a short sequence read back as TUM.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/sim/synthetic_scene.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using V = Eigen::Vector3d;

TEST(SyntheticScene, RaysHitWallsFloorAndSpheresWhereComputedByHand) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  double t = 0.0;
  V n;
  cv::Vec3b color;
  // From the room's centre at 1.4 m: the wall x = 2.5 is 2.5 m away, facing back at us.
  ASSERT_TRUE(scene.raycast(V(0, 0, 1.4), V(1, 0, 0), t, n, color));
  EXPECT_NEAR(t, 2.5, 1e-12);
  EXPECT_TRUE(n.isApprox(V(-1, 0, 0)));
  // t is in units of the direction's length: a direction of length 2 halves it.
  ASSERT_TRUE(scene.raycast(V(0, 0, 1.4), V(2, 0, 0), t, n, color));
  EXPECT_NEAR(t, 1.25, 1e-12);
  // Straight down onto the floor; the colour is the floor texture's at (x, y), in BGR.
  ASSERT_TRUE(scene.raycast(V(0.3, 0.1, 1.4), V(0, 0, -1), t, n, color));
  EXPECT_NEAR(t, 1.4, 1e-12);
  EXPECT_TRUE(n.isApprox(V(0, 0, 1)));
  const cv::Vec3b rgb = scene.room().texture.colorAt(0.3, 0.1);
  EXPECT_EQ(color, cv::Vec3b(rgb[2], rgb[1], rgb[0]));
  // The ball (centre (1.5, 1.2, 0.35), radius 0.35) from its side at its centre height.
  ASSERT_TRUE(scene.raycast(V(0, 1.2, 0.35), V(1, 0, 0), t, n, color));
  EXPECT_NEAR(t, 1.5 - 0.35, 1e-12);
  EXPECT_TRUE(n.isApprox(V(-1, 0, 0)));
  // A diagonal ray at the ball: hits where |o + t d - c| = r.
  const V origin(0.5, 0.2, 1.0), direction = (V(1.5, 1.2, 0.35) - origin).normalized();
  ASSERT_TRUE(scene.raycast(origin, direction, t, n, color));
  EXPECT_NEAR(t, (V(1.5, 1.2, 0.35) - origin).norm() - 0.35, 1e-12);
  EXPECT_TRUE(n.isApprox(-direction));
  // Down onto the ball sitting on the red cube: its top is at 0.5 + 2 * 0.25 = 1.0.
  ASSERT_TRUE(scene.raycast(V(-1.55, -1.25, 2.0), V(0, 0, -1), t, n, color));
  EXPECT_NEAR(t, 1.0, 1e-12);
  // Down onto the table top (0.75) beside the objects on it.
  ASSERT_TRUE(scene.raycast(V(0.7, -1.5, 2.0), V(0, 0, -1), t, n, color));
  EXPECT_NEAR(t, 2.0 - 0.75, 1e-12);
  // A lone sphere is missed by a ray pointing away from it.
  SyntheticScene lone;
  lone.addSphere(V(0, 0, 5), 1.0, SurfaceTexture{}, "sphere");
  EXPECT_FALSE(lone.raycast(V(0, 0, 0), V(0, 0, -1), t, n, color));
  ASSERT_TRUE(lone.raycast(V(0, 0, 0), V(0, 0, 1), t, n, color));
  EXPECT_NEAR(t, 4.0, 1e-12);
}

TEST(SyntheticScene, DistanceToTheNearestSurfaceIsExact) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  // From the room's centre the nearest surface is the table's top corner (0.6, -0.8, 0.75),
  // nearer than floor and ceiling (1.4).
  EXPECT_NEAR(scene.distance(V(0, 0, 1.4)), std::sqrt(0.6 * 0.6 + 0.8 * 0.8 + 0.65 * 0.65), 1e-12);
  EXPECT_NEAR(scene.distance(V(0, 0.5, 1.6)), 1.2, 1e-12);      // ceiling
  EXPECT_NEAR(scene.distance(V(0, 0, 0.3)), 0.3, 1e-12);        // floor
  EXPECT_NEAR(scene.distance(V(2.4, 0, 1.4)), 0.1, 1e-12);      // wall x = 2.5
  EXPECT_NEAR(scene.distance(V(1.2, -1.2, 0.5)), 0.25, 1e-12);  // inside the table, under its top
  EXPECT_NEAR(scene.distance(V(1.85, 1.2, 0.35)), 0.0, 1e-12);  // on the ball
  EXPECT_NEAR(scene.distance(V(1.5, 1.2, 0.45)), 0.25, 1e-12);  // inside the ball
  // Outside a corner of the table top: distance to the edge, not to either face's plane.
  EXPECT_NEAR(scene.distance(V(1.83, -0.76, 0.75)), 0.05, 1e-12);
  EXPECT_TRUE(scene.isFreeSpace(V(0, 0, 1.4), 0.25));
  EXPECT_FALSE(scene.isFreeSpace(V(1.2, -1.2, 0.5), 0.0));  // in the table
  EXPECT_FALSE(scene.isFreeSpace(V(3.0, 0.0, 1.4), 0.0));   // outside the room
  EXPECT_FALSE(scene.isFreeSpace(V(0.0, 0.0, 0.1), 0.25));  // too near the floor
}

TEST(SyntheticScene, YamlRoundTripKeepsEveryPrimitive) {
  const std::string dir = test::freshDir();
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  scene.save(dir + "/scene.yaml");
  const SyntheticScene loaded = SyntheticScene::load(dir + "/scene.yaml");
  ASSERT_EQ(loaded.primitives().size(), scene.primitives().size());
  for (std::size_t i = 0; i < scene.primitives().size(); ++i) {
    const ScenePrimitive& a = scene.primitives()[i];
    const ScenePrimitive& b = loaded.primitives()[i];
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.name, b.name);
    if (a.kind == ScenePrimitive::Kind::kSphere) {
      EXPECT_EQ(a.center, b.center);
      EXPECT_EQ(a.radius, b.radius);
    } else {
      EXPECT_EQ(a.min, b.min);
      EXPECT_EQ(a.max, b.max);
    }
    EXPECT_EQ(a.texture.pattern, b.texture.pattern);
    EXPECT_EQ(a.texture.color_a, b.texture.color_a);
    EXPECT_EQ(a.texture.color_b, b.texture.color_b);
    EXPECT_EQ(a.texture.scale, b.texture.scale);
    EXPECT_EQ(a.texture.angle_deg, b.texture.angle_deg);
  }
  for (const V& p : {V(0.1, 0.2, 0.3), V(-2, 1.5, 2.5), V(1.5, -1, 0.9)})
    EXPECT_EQ(scene.distance(p), loaded.distance(p));
}

TEST(SyntheticScene, BadYamlNamesFileLineAndProblem) {
  const std::string dir = test::freshDir();
  const std::string path = dir + "/scene.yaml";
  std::ofstream(path)
      << "primitives:\n"
         "  - kind: room\n    min: [-1, -1, 0]\n    max: [1, 1, 2]\n"
         "    texture: {pattern: checker, color_a: [1, 2, 3], color_b: [4, 5, 6], scale: 0.2}\n"
         "  - kind: cone\n    texture: {pattern: checker, color_a: [1, 2, 3], color_b: [4, 5, 6], "
         "scale: 0.2}\n";
  try {
    SyntheticScene::load(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path + ":6"), std::string::npos) << message;
    EXPECT_NE(message.find("cone"), std::string::npos) << message;
  }
  std::ofstream(path) << "primitives:\n  - kind: sphere\n    center: [0, 0]\n";
  EXPECT_THROW(SyntheticScene::load(path), InputError);
  EXPECT_THROW(SyntheticScene::load(dir + "/missing.yaml"), InputError);
}

TEST(SyntheticScene, HandheldPathStaysInFreeSpaceForAnySeed) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const HandheldPath path(scene.room(), seed, 12.0);
    for (double t = 0.0; t < 60.0; t += 0.01)
      ASSERT_TRUE(scene.isFreeSpace(path.pose(t).translation(), 0.25))
          << "seed " << seed << " t " << t;
  }
}

// One noisy and one noise-free 20-frame sequence with the same seed (hence the same path),
// written once for all the tests below.
class SyntheticSequenceTest : public ::testing::Test {
 protected:
  static constexpr int kFrames = 20;
  static constexpr std::uint64_t kSeed = 7;
  static std::string noisy_, clean_;

  static void SetUpTestSuite() {
    // CTest runs each test of this suite as its own process: the first writes the sequences,
    // the others read them.
    const std::string root = test::writeOnce(
        std::string(RGBDMAP_TEST_TMP) + "/SyntheticSequenceTest", [](const std::string& folder) {
          SyntheticSequenceOptions options;
          options.frames = kFrames;
          options.seed = kSeed;
          writeSyntheticSequence(folder + "/noisy", SyntheticScene::defaultRoom(), options);
          options.noise = false;
          writeSyntheticSequence(folder + "/clean", SyntheticScene::defaultRoom(), options);
        });
    noisy_ = root + "/noisy";
    clean_ = root + "/clean";
  }
};
std::string SyntheticSequenceTest::noisy_;
std::string SyntheticSequenceTest::clean_;

TEST_F(SyntheticSequenceTest, LoadsAsTumWithEveryFrameAndPose) {
  TumSequence sequence(noisy_);
  ASSERT_EQ(sequence.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(sequence.unmatchedColor(), 0u);
  EXPECT_EQ(sequence.unmatchedDepth(), 0u);
  EXPECT_EQ(sequence.framesWithoutPose(), 0u);
  EXPECT_EQ(TumSequence::presetForFolder(noisy_), "");  // the default intrinsics apply
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const double offset = sequence[i].depth_time - sequence[i].rgb_time;
    EXPECT_GT(offset, 0.001);
    EXPECT_LT(offset, 0.02);
  }
  Frame frame;
  std::string error;
  ASSERT_TRUE(sequence.load(3, frame, error)) << error;
  EXPECT_EQ(frame.depth.size(), cv::Size(640, 480));
  EXPECT_EQ(frame.color.type(), CV_8UC3);
  // Ground truth covers the frames with 100 Hz samples before and after.
  const Trajectory& gt = sequence.groundtruth();
  EXPECT_LT(gt[0].timestamp, sequence[0].rgb_time);
  EXPECT_GT(gt[gt.size() - 1].timestamp, sequence[sequence.size() - 1].rgb_time);
  EXPECT_NEAR(gt[1].timestamp - gt[0].timestamp, 0.01, 1e-6);
  EXPECT_TRUE(std::filesystem::exists(noisy_ + "/scene.yaml"));
}

TEST_F(SyntheticSequenceTest, InterpolatedGroundTruthMatchesTheAnalyticPath) {
  const TumSequence sequence(noisy_);
  const SyntheticSequenceOptions defaults;
  const HandheldPath path(SyntheticScene::defaultRoom().room(), kSeed, defaults.loop_seconds);
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    ASSERT_TRUE(sequence[i].pose.has_value());
    const Eigen::Isometry3d truth = path.pose(sequence[i].rgb_time - defaults.start_time);
    const Eigen::Isometry3d& pose = *sequence[i].pose;
    // Linear interpolation over 10 ms of a smooth path: well under 0.1 mm and 0.01 degrees.
    EXPECT_LT((pose.translation() - truth.translation()).norm(), 1e-4) << "frame " << i;
    EXPECT_LT(Eigen::AngleAxisd(pose.linear().transpose() * truth.linear()).angle(), 2e-4)
        << "frame " << i;
  }
}

TEST_F(SyntheticSequenceTest, NoiseFreeDepthIsTheRayCastZDepthAtTheGroundTruthPose) {
  TumSequence sequence(clean_);
  const SyntheticScene scene = SyntheticScene::load(clean_ + "/scene.yaml");
  const CameraIntrinsics camera;
  Frame frame;
  std::string error;
  std::size_t compared = 0;
  for (std::size_t i : {0u, 9u, 19u}) {
    ASSERT_TRUE(sequence.load(i, frame, error)) << error;
    const Eigen::Isometry3d pose = *sequence[i].pose;
    for (int v = 0; v < camera.height; v += 7) {
      for (int u = 0; u < camera.width; u += 7) {
        const V ray((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
        double t = 0.0;
        V n;
        cv::Vec3b c;
        ASSERT_TRUE(scene.raycast(pose.translation(), pose.linear() * ray, t, n, c));
        const float depth = frame.depth.at<float>(v, u);
        if (depth == 0.0f) {
          // Missing only outside the range or at grazing incidence.
          const double cos_incidence = -n.dot(pose.linear() * ray) / ray.norm();
          EXPECT_TRUE(t < 0.5 + 1e-3 || t > 4.5 - 1e-3 || cos_incidence < 0.21)
              << "pixel " << u << "," << v << " t " << t;
          continue;
        }
        // Quantisation (0.1 mm) plus the ground-truth interpolation's error.
        EXPECT_NEAR(depth, t, 0.0003) << "frame " << i << " pixel " << u << "," << v;
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 12000u);
}

TEST_F(SyntheticSequenceTest, DepthNoiseFollowsTheKinectModel) {
  TumSequence noisy(noisy_), clean(clean_);
  // Bins of true depth: the residual divided by sigma(z) must be a unit Gaussian.
  const std::vector<double> edges = {0.5, 1.0, 1.5, 2.0, 2.5, 3.5, 4.5};
  std::vector<double> sum(edges.size(), 0.0), squares(edges.size(), 0.0);
  std::vector<std::size_t> count(edges.size(), 0);
  std::size_t clean_valid = 0, dropped = 0;
  Frame a, b;
  std::string error;
  for (std::size_t i = 0; i < noisy.size(); ++i) {
    ASSERT_TRUE(noisy.load(i, a, error)) << error;
    ASSERT_TRUE(clean.load(i, b, error)) << error;
    for (int v = 0; v < a.depth.rows; ++v) {
      for (int u = 0; u < a.depth.cols; ++u) {
        const double z = b.depth.at<float>(v, u), measured = a.depth.at<float>(v, u);
        if (z == 0.0) continue;
        ++clean_valid;
        if (measured == 0.0) {
          ++dropped;
          continue;
        }
        const std::size_t bin = static_cast<std::size_t>(
            std::upper_bound(edges.begin(), edges.end(), z) - edges.begin() - 1);
        const double normalised = (measured - z) / kinectDepthSigma(z);
        sum[bin] += normalised;
        squares[bin] += normalised * normalised;
        ++count[bin];
      }
    }
  }
  std::size_t bins_tested = 0;
  for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
    if (count[k] < 5000) continue;
    ++bins_tested;
    const double mean = sum[k] / count[k];
    const double std = std::sqrt(squares[k] / count[k] - mean * mean);
    EXPECT_NEAR(mean, 0.0, 0.05) << "z in [" << edges[k] << ", " << edges[k + 1] << ")";
    EXPECT_NEAR(std, 1.0, 0.05) << "z in [" << edges[k] << ", " << edges[k + 1] << ")";
    std::cout << "z in [" << edges[k] << ", " << edges[k + 1] << "): " << count[k]
              << " pixels, residual/sigma(z) mean " << mean << " std " << std << "\n";
  }
  EXPECT_GE(bins_tested, 3u);
  // Random dropouts of 2 % (plus the few that noise pushes out of range).
  const double dropout = static_cast<double>(dropped) / clean_valid;
  EXPECT_GT(dropout, 0.015);
  EXPECT_LT(dropout, 0.03);
}

TEST_F(SyntheticSequenceTest, SameSeedSameImagesOtherSeedOtherNoise) {
  const std::string root = test::freshDir();
  SyntheticSequenceOptions options;
  options.frames = 2;
  options.seed = kSeed;
  writeSyntheticSequence(root + "/again", SyntheticScene::defaultRoom(), options);
  options.seed = kSeed + 1;
  writeSyntheticSequence(root + "/other", SyntheticScene::defaultRoom(), options);
  const TumSequence first(noisy_), again(root + "/again"), other(root + "/other");
  const cv::Mat a = cv::imread(first[1].depth_path, cv::IMREAD_UNCHANGED);
  const cv::Mat b = cv::imread(again[1].depth_path, cv::IMREAD_UNCHANGED);
  const cv::Mat c = cv::imread(other[1].depth_path, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(cv::imread(first[1].rgb_path), cv::imread(again[1].rgb_path), cv::NORM_INF),
            0.0);
}

TEST_F(SyntheticSequenceTest, NoiseSeedChangesTheNoiseNotThePath) {
  // A second pass over the same path with fresh sensor noise (issue 11's revisit test).
  const std::string root = test::freshDir();
  SyntheticSequenceOptions options;
  options.frames = 2;
  options.seed = kSeed;
  options.noise_seed = options.noise_seed + 1;
  writeSyntheticSequence(root + "/fresh", SyntheticScene::defaultRoom(), options);
  const TumSequence first(noisy_), fresh(root + "/fresh");
  ASSERT_TRUE(first[1].pose.has_value() && fresh[1].pose.has_value());
  EXPECT_TRUE(first[1].pose->isApprox(*fresh[1].pose, 1e-9));
  const cv::Mat a = cv::imread(first[1].depth_path, cv::IMREAD_UNCHANGED);
  const cv::Mat b = cv::imread(fresh[1].depth_path, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(b.empty());
  EXPECT_GT(cv::norm(a, b, cv::NORM_INF), 0.0);
}

TEST(SyntheticScene, ALargerRoomKeepsItsFurnitureInside) {
  const SyntheticScene scene = SyntheticScene::defaultRoom(Eigen::Vector3d(6.0, 5.0, 3.0));
  const ScenePrimitive& room = scene.room();
  EXPECT_EQ(room.max - room.min, Eigen::Vector3d(6.0, 5.0, 3.0));
  for (const ScenePrimitive& p : scene.primitives()) {
    if (p.kind == ScenePrimitive::Kind::kBox) {
      EXPECT_TRUE((p.min.array() >= room.min.array()).all() &&
                  (p.max.array() <= room.max.array()).all())
          << p.name;
    } else if (p.kind == ScenePrimitive::Kind::kSphere) {
      EXPECT_TRUE((p.center.array() - p.radius >= room.min.array()).all() &&
                  (p.center.array() + p.radius <= room.max.array()).all())
          << p.name;
    }
  }
  const HandheldPath path(room, 3, 12.0);
  for (double t = 0.0; t < 12.0; t += 0.05)
    EXPECT_TRUE(scene.isFreeSpace(path.pose(t).translation(), 0.25)) << "t = " << t;
}

TEST_F(SyntheticSequenceTest, VisibleSurfaceSamplesLieExactlyOnTheScene) {
  pcl::PointCloud<pcl::PointXYZ> surface;
  ASSERT_EQ(pcl::io::loadPCDFile(noisy_ + "/visible_surface.pcd", surface), 0);
  ASSERT_GT(surface.size(), 50000u);
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  double worst = 0.0;
  for (const pcl::PointXYZ& p : surface) worst = std::max(worst, scene.distance(V(p.x, p.y, p.z)));
  EXPECT_LT(worst, 1e-5);  // float storage only
}

TEST(SyntheticSequence, RejectsOptionsOutsideTheModel) {
  const std::string dir = test::freshDir();
  SyntheticSequenceOptions options;
  options.frames = 0;
  EXPECT_THROW(writeSyntheticSequence(dir, SyntheticScene::defaultRoom(), options), InputError);
  options = SyntheticSequenceOptions{};
  options.depth_offset = 0.03;  // outside the association window
  EXPECT_THROW(writeSyntheticSequence(dir, SyntheticScene::defaultRoom(), options), InputError);
  // A room too small for the path to keep its distance from the walls.
  SyntheticScene closet;
  closet.addRoom(V(0, 0, 0), V(0.6, 0.6, 2.5), SurfaceTexture{});
  options = SyntheticSequenceOptions{};
  EXPECT_THROW(writeSyntheticSequence(dir, closet, options), InputError);
}

}  // namespace
}  // namespace rgbdmap
