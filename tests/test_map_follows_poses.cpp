// The map follows its poses (Mapper with loop closure): kept keyframes are fused again when a loop
// moves them, so two visits of a wall left a few millimetres apart give one surface, and a camera
// that stays in one place keeps one keyframe's images, not one per frame.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <unordered_map>

#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

// A camera 2 m from the +x wall of the 5 x 4 m room, looking at it, sliding sideways.
std::vector<Frame> wallViews(const Config& config) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  SyntheticRenderer renderer(scene, config.camera);
  Eigen::Matrix3d looking_at_x;
  looking_at_x << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  std::vector<Frame> views(8);
  for (std::size_t i = 0; i < views.size(); ++i) {
    Frame& f = views[i];
    f.pose.linear() = looking_at_x;
    f.pose.translation() = Eigen::Vector3d(0.5, -0.3 + 0.08 * static_cast<double>(i), 1.4);
    cv::Mat incidence, hits;
    renderer.render(f.pose, f.depth, f.color, incidence, hits);
    f.has_pose = true;
  }
  return views;
}

// `views` views round a circle of 0.8 m at the room's centre, looking out: with 24 each viewpoint
// is 0.7 m (KeyframeStore's measure) from the next, with 72 0.24 m; none is seen twice in a lap.
std::vector<Frame> lapViews(const Config& config, std::size_t views = 24) {
  const SyntheticScene scene = SyntheticScene::defaultRoom();
  SyntheticRenderer renderer(scene, config.camera);
  std::vector<Frame> lap(views);
  for (std::size_t i = 0; i < lap.size(); ++i) {
    const double angle = 2.0 * M_PI * static_cast<double>(i) / static_cast<double>(lap.size());
    const Eigen::Vector3d out(std::cos(angle), std::sin(angle), 0.0);
    Frame& f = lap[i];
    f.pose.linear().col(0) = Eigen::Vector3d(out.y(), -out.x(), 0.0);
    f.pose.linear().col(1) = Eigen::Vector3d(0.0, 0.0, -1.0);
    f.pose.linear().col(2) = out;
    f.pose.translation() = 0.8 * out + Eigen::Vector3d(0.0, 0.0, 1.4);
    cv::Mat incidence, hits;
    renderer.render(f.pose, f.depth, f.color, incidence, hits);
    f.has_pose = true;
  }
  return lap;
}

// Fuses one lap (anchor 0), closes a loop that moves it by 4 mm, and lets the map follow.
void fuseALapAndCloseItsLoop(Mapper& mapper, PoseCorrections& corrections,
                             const std::vector<Frame>& lap) {
  for (std::size_t i = 0; i < lap.size(); ++i) {
    Frame f = lap[i];
    f.anchor = 0;
    f.index = i;
    f.timestamp = static_cast<double>(i) / 30.0;
    mapper.fuse(f);
  }
  Eigen::Isometry3d pulled = Eigen::Isometry3d::Identity();
  pulled.translation().x() = 0.004;
  corrections.publish({pulled});
  mapper.settle();
}

// Fuses `visits` visits of the wall, each its own anchor; odometry put the second visit 5 cm
// nearer the wall than it was.
void fuseVisits(Mapper& mapper, const std::vector<Frame>& views, int visits) {
  for (int visit = 0; visit < visits; ++visit) {
    for (Frame f : views) {
      f.anchor = visit;
      f.index = static_cast<std::uint64_t>(visit) * views.size() + f.index;
      if (visit == 1) f.pose.translation().x() += 0.05;
      mapper.fuse(f);
    }
  }
}

// What a loop closure publishes for the second visit: back but for a 4 mm residual (what the
// graph leaves on real data).
void closeTheLoop(PoseCorrections& corrections) {
  Eigen::Isometry3d back = Eigen::Isometry3d::Identity();
  back.translation().x() = -0.05 + 0.004;
  corrections.publish({Eigen::Isometry3d::Identity(), back});
}

// Two visits of one wall, the second tracked 5 cm off; a loop closure then puts it back but for
// a 4 mm residual. The map written must be one layer, as the same frames fused into one TSDF at
// the corrected poses give: surface points merged voxel by voxel (the design before) kept about
// 1.4 times the points, two layers wherever the 4 mm straddled a voxel boundary.
TEST(MapFollowsPoses, ASecondVisitLeftAFewMillimetresOffIsOneLayer) {
  Config config;
  const std::vector<Frame> views = wallViews(config);
  auto fused = [&](int visits, bool loop_closed) {
    RunStats stats;
    PoseCorrections corrections;
    corrections.publish({Eigen::Isometry3d::Identity()});
    Mapper mapper(config.camera, config.filter, config.map, config.refusion, stats, &corrections);
    fuseVisits(mapper, views, visits);
    if (loop_closed) closeTheLoop(corrections);
    mapper.settle();
    return mapper.snapshot()->size();
  };
  const std::size_t once = fused(1, false);
  const std::size_t drifted = fused(2, false);
  const std::size_t corrected = fused(2, true);
  ASSERT_GT(once, 50000u);
  EXPECT_GT(static_cast<double>(drifted), 1.6 * static_cast<double>(once));  // two layers
  EXPECT_LT(static_cast<double>(corrected), 1.1 * static_cast<double>(once))
      << "one visit " << once << ", two drifted " << drifted << ", two corrected " << corrected;
}

// While a pass re-fuses the map, what is shown and written is the whole map it began from (not
// the part re-fused so far), and memory holds one TSDF (emptied, its memory reused) and that
// map's cloud: a pass into a second TSDF beside the first (the design before) took 100 MB more at
// the peak of a 10-lap walk.
TEST(MapFollowsPoses, APassShowsTheMapItBeganFromAndHoldsOneTsdf) {
  Config config;
  config.refusion.refusion_pace = 1;
  const std::vector<Frame> views = wallViews(config);
  RunStats stats;
  PoseCorrections corrections;
  corrections.publish({Eigen::Isometry3d::Identity()});
  Mapper mapper(config.camera, config.filter, config.map, config.refusion, stats, &corrections);
  fuseVisits(mapper, views, 2);
  const std::size_t drifted = mapper.snapshot()->size();
  const std::size_t before = mapper.memoryBytes();
  closeTheLoop(corrections);
  ASSERT_TRUE(mapper.refine(1));  // the pass begins, one keyframe re-fused
  EXPECT_EQ(mapper.snapshot()->size(), drifted);
  // (The packed cloud is reserved with room for a sixteenth more.)
  EXPECT_LE(mapper.memoryBytes(), before + (drifted + drifted / 16 + 512) * sizeof(PackedMapPoint));
  // A keyframe arriving meanwhile waits for the pass, which takes it in.
  Frame late = views.front();
  late.anchor = 0;
  late.index = 100;
  mapper.fuse(late);
  EXPECT_EQ(mapper.snapshot()->size(), drifted);
  mapper.settle();
  EXPECT_EQ(stats.map_refusions.load(), 1u);
  EXPECT_EQ(stats.keyframes_refused.load(), 2 * views.size() + 1);
  EXPECT_LT(static_cast<double>(mapper.snapshot()->size()), 0.6 * static_cast<double>(drifted));
  EXPECT_LE(mapper.memoryBytes(), before);  // one layer: no more blocks than two
}

// Memory is bounded: a camera at rest, fused frame after frame with loop closure on, keeps images
// up to the budget and no more (a soak at rest once grew 10 MB a minute); a viewpoint seen once
// is kept while copies of the crowded one are let go.
TEST(KeptKeyframes, ACameraAtRestStaysWithinBudgetAndAViewSeenOnceIsKept) {
  const std::string folder = test::tumDir(test::kXyz);
  Config config;
  config.loadPreset(TumSequence::presetForFolder(folder));
  config.refusion.keyframe_memory = 2.0;  // MB: about ten keyframes
  TumSequence sequence(folder);
  Frame frame;
  std::string error;
  ASSERT_TRUE(sequence.load(0, frame, error)) << error;
  RunStats stats;
  PoseCorrections corrections;
  Mapper mapper(config.camera, config.filter, config.map, config.refusion, stats, &corrections);
  frame.anchor = 0;
  auto rest = [&](int frames) {
    for (int i = 0; i < frames; ++i) {
      frame.timestamp += 1.0 / 30;
      mapper.fuse(frame);
    }
  };
  rest(30);
  const std::size_t bytes_after_a_while = mapper.memoryBytes();
  rest(30);
  const KeyframeStore& kept = mapper.keptKeyframes();
  EXPECT_GT(kept.size(), 3u);
  EXPECT_LT(kept.size(), 30u);
  EXPECT_LE(kept.memoryBytes(), 2u * 1024 * 1024 + kept.size() * sizeof(KeyframeStore::Entry));
  EXPECT_EQ(mapper.memoryBytes(), bytes_after_a_while);
  const std::size_t at_rest = kept.size();
  // One look from a metre away, then back at rest for a while.
  const Eigen::Isometry3d rest_pose = frame.pose;
  frame.pose.translation().x() += 1.0;
  frame.timestamp += 1.0 / 30;
  mapper.fuse(frame);
  const double seen_once = frame.timestamp;
  frame.pose = rest_pose;
  rest(30);
  EXPECT_EQ(kept.size(), at_rest);
  bool kept_it = false;
  for (std::size_t i = 0; i < kept.size(); ++i) kept_it = kept_it || kept[i].timestamp == seen_once;
  EXPECT_TRUE(kept_it) << "the view seen once was let go";
}

// Memory follows space, not time: a camera going round the room again and again, each lap pulled
// a few millimetres by the loop it closes (so that the map is fused again), holds after each lap
// from the third on what it held after the second: the kept keyframes stay within their budget,
// each pass fuses into the TSDF's memory and gives back what it no longer needs, and nothing is
// kept per lap. (Closed submaps, the design before, added a copy of the room's surface every lap.)
TEST(KeptKeyframes, LapsOfTheRoomHoldAfterTheSixthWhatTheyHeldAfterTheSecond) {
  Config config;
  config.refusion.keyframe_memory = 1.0;  // MB: about 16 of a lap's 24 views
  const std::vector<Frame> lap = lapViews(config);
  RunStats stats;
  PoseCorrections corrections;
  Mapper mapper(config.camera, config.filter, config.map, config.refusion, stats, &corrections);
  std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>> table;
  std::vector<std::size_t> memory;
  for (int round = 0; round < 6; ++round) {
    for (std::size_t i = 0; i < lap.size(); ++i) {
      Frame f = lap[i];
      f.anchor = round;
      f.index = static_cast<std::uint64_t>(round) * lap.size() + i;
      f.timestamp = static_cast<double>(f.index) / 30.0;
      mapper.fuse(f);
    }
    // The loop closed at the lap's end moves it by 4 mm, one way or the other.
    Eigen::Isometry3d pulled = Eigen::Isometry3d::Identity();
    pulled.translation().x() = (round % 2 == 0 ? 0.004 : -0.004);
    table.push_back(pulled);
    corrections.publish(table);
    mapper.settle();
    memory.push_back(mapper.memoryBytes());
    std::cout << "lap " << round + 1 << ": " << memory.back() / 1024 << " KB, "
              << mapper.keptKeyframes().size() << " keyframes kept, " << stats.map_refusions.load()
              << " passes\n";
  }
  EXPECT_GE(stats.map_refusions.load(), 5u);
  EXPECT_LT(mapper.keptKeyframes().size(), 6 * lap.size());
  // Within 5% (which keyframes are kept, and so the TSDF's fringes, alternates with the pull's
  // direction: 1 MB of 38); a copy of the room's surface per lap would be half as much again.
  for (std::size_t round = 2; round < memory.size(); ++round)
    EXPECT_LE(memory[round], memory[1] + memory[1] / 20) << "lap " << round + 1;
}

// Nothing seen is forgotten: a space walked once, its views 0.24 m apart, with a budget that holds
// a few of its keyframes' images, keeps the rest on disk, and a pass after a loop fuses them all:
// the map it gives is the one an unbounded budget gives, voxel for voxel. (Before, views within
// 0.3 m of another were thinned, and what only the ones let go saw left the map at the pass; and
// before that, the older of the two nearest views was let go.)
TEST(KeptKeyframes, ASpaceWalkedOnceBeyondTheBudgetIsKeptOnDiskAndStaysInTheMap) {
  Config config;
  const std::vector<Frame> lap = lapViews(config, 72);
  auto mapLap = [&](double budget_mb, RunStats& stats, std::size_t& on_disk,
                    std::size_t& image_bytes) {
    config.refusion.keyframe_memory = budget_mb;
    PoseCorrections corrections;
    Mapper mapper(config.camera, config.filter, config.map, config.refusion, stats, &corrections);
    fuseALapAndCloseItsLoop(mapper, corrections, lap);
    EXPECT_EQ(stats.map_refusions.load(), 1u);
    EXPECT_EQ(mapper.keptKeyframes().size(), lap.size());
    on_disk = mapper.keptKeyframes().onDisk();
    image_bytes = 0;
    for (std::size_t k = 0; k < lap.size(); ++k)
      image_bytes += mapper.keptKeyframes()[k].imageBytes();
    // A session saves every kept keyframe, those on disk read back.
    const std::vector<KeyframeStore::Entry> saved = mapper.keptKeyframes().entries();
    EXPECT_EQ(saved.size(), lap.size());
    for (const KeyframeStore::Entry& e : saved) {
      EXPECT_GT(e.depthImage()->size(), 1000u);
      EXPECT_GT(e.colourImage()->size(), 1000u);
    }
    return mapper.snapshot();
  };
  RunStats unbounded_stats, bounded_stats;
  std::size_t unbounded_on_disk = 0, bounded_on_disk = 0, unbounded_bytes = 0, bounded_bytes = 0;
  const auto unbounded = mapLap(1000.0, unbounded_stats, unbounded_on_disk, unbounded_bytes);
  const auto bounded = mapLap(0.25, bounded_stats, bounded_on_disk, bounded_bytes);
  std::cout << "unbounded: " << unbounded->size() << " points, " << unbounded_bytes / 1024
            << " KB of images in memory; 0.25 MB: " << bounded->size() << " points, "
            << bounded_bytes / 1024 << " KB in memory, " << bounded_on_disk
            << " keyframes on disk\n";
  EXPECT_EQ(unbounded_on_disk, 0u);
  EXPECT_GT(bounded_on_disk, lap.size() / 2);
  EXPECT_LE(bounded_bytes, static_cast<std::size_t>(0.25 * 1024 * 1024));
  ASSERT_GT(unbounded->size(), 10000u);
  ASSERT_EQ(bounded->size(), unbounded->size());
  for (std::size_t i = 0; i < bounded->size(); ++i)
    ASSERT_EQ((*bounded)[i].getVector3fMap(), (*unbounded)[i].getVector3fMap()) << i;
}

// A loop that moves part of the map fuses again only that part: a lap of 36 views round the room,
// which a first loop moves whole (a whole pass), and whose first twelfth a second loop then moves
// by 4 mm. The second pass fuses the cells those views see, before and after, from the keyframes
// that see them (not the whole lap), and gives the map a whole pass gives, voxel for voxel; so
// does a map with most of its blocks on disk (map.memory).
TEST(MapFollowsPoses, ALoopThatMovesPartOfTheMapFusesOnlyThatPartAgain) {
  Config config;
  const std::vector<Frame> lap = lapViews(config, 36);
  auto mapLap = [&](double region_share, double memory_mb, RunStats& stats) {
    config.refusion.region_share = region_share;
    config.map.memory = memory_mb;
    PoseCorrections corrections;
    Mapper mapper(config.camera, config.filter, config.map, config.refusion, stats, &corrections);
    for (std::size_t i = 0; i < lap.size(); ++i) {
      Frame f = lap[i];
      f.anchor = i < lap.size() / 12 ? 1 : 0;
      f.index = i;
      f.timestamp = static_cast<double>(i) / 30.0;
      mapper.fuse(f);
    }
    // After the first pass the map is fused from the kept keyframes' images everywhere (a
    // keyframe fused as it comes is fused from its own, which the store keeps compressed).
    Eigen::Isometry3d everything = Eigen::Isometry3d::Identity();
    everything.translation().x() = 0.004;
    corrections.publish({everything, everything});
    mapper.settle();
    Eigen::Isometry3d pulled = everything;
    pulled.translation() += Eigen::Vector3d(0.003, -0.002, 0.001);
    corrections.publish({everything, pulled});
    mapper.settle();
    return mapper.snapshot();
  };
  RunStats region_stats, whole_stats, bounded_stats;
  const auto region = mapLap(RefusionOptions().region_share, 0.0, region_stats);
  const auto whole = mapLap(0.0, 0.0, whole_stats);
  // With 2 MB of blocks in memory (a tenth of the map), the rest on disk: the same map again.
  const auto bounded = mapLap(RefusionOptions().region_share, 2.0, bounded_stats);
  const std::size_t second_pass = region_stats.keyframes_refused.load() - lap.size();
  std::cout << "second pass: " << second_pass << " of " << lap.size() << " keyframes; "
            << region->size() << " points, a whole pass " << whole->size() << "\n";
  EXPECT_EQ(region_stats.map_refusions.load(), 2u);
  EXPECT_EQ(region_stats.region_refusions.load(), 1u);
  EXPECT_EQ(whole_stats.region_refusions.load(), 0u);
  EXPECT_EQ(whole_stats.keyframes_refused.load(), 2 * lap.size());
  EXPECT_LE(second_pass, lap.size() / 2);
  EXPECT_GT(second_pass, lap.size() / 12);
  ASSERT_GT(whole->size(), 100000u);
  ASSERT_EQ(region->size(), whole->size());
  // The same points (blocks may be stored in another order).
  std::unordered_map<std::uint64_t, Eigen::Vector3f> by_voxel;
  VoxelMap keys(config.map.voxel_size);
  for (const auto& p : *whole) {
    std::uint64_t key;
    ASSERT_TRUE(keys.keyFor(p.getVector3fMap(), key));
    by_voxel[key] = p.getVector3fMap();
  }
  // Points of a map that the whole pass has, at the same place in the same voxel.
  const auto sameAsWhole = [&](const MapCloud& map) {
    std::size_t same = 0;
    for (const auto& p : map) {
      std::uint64_t key;
      if (!keys.keyFor(p.getVector3fMap(), key)) continue;
      const auto it = by_voxel.find(key);
      if (it != by_voxel.end() && it->second == p.getVector3fMap()) ++same;
    }
    return same;
  };
  EXPECT_EQ(sameAsWhole(*region), whole->size());
  std::cout << bounded_stats.map_blocks_stored.load() << " blocks went to disk with 2 MB\n";
  EXPECT_GT(bounded_stats.map_blocks_stored.load(), 1000u);
  EXPECT_EQ(bounded_stats.region_refusions.load(), 1u);
  ASSERT_EQ(bounded->size(), whole->size());
  EXPECT_EQ(sameAsWhole(*bounded), whole->size());
}

// A disk that refuses (TMPDIR a folder that is not there) is said once, and the store falls back
// to letting the oldest unique views go: the run goes on within its memory budget.
TEST(KeptKeyframes, ADiskThatRefusesLetsViewsGoAndTheRunGoesOn) {
  const char* before = std::getenv("TMPDIR");
  const std::string saved = before ? before : "";
  ::setenv("TMPDIR", "/nonexistent/rgbdmap-test", 1);
  Config config;
  config.refusion.keyframe_memory = 0.25;
  const std::vector<Frame> lap = lapViews(config);
  RunStats stats;
  PoseCorrections corrections;
  Mapper mapper(config.camera, config.filter, config.map, config.refusion, stats, &corrections);
  fuseALapAndCloseItsLoop(mapper, corrections, lap);
  if (before)
    ::setenv("TMPDIR", saved.c_str(), 1);
  else
    ::unsetenv("TMPDIR");
  EXPECT_EQ(mapper.keptKeyframes().onDisk(), 0u);
  EXPECT_LT(mapper.keptKeyframes().size(), lap.size());
  EXPECT_EQ(stats.map_refusions.load(), 1u);
  EXPECT_GT(mapper.snapshot()->size(), 1000u);
}

}  // namespace
}  // namespace rgbdmap
