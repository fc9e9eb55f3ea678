// A run that continues a saved session (--continue MAP.session) on real frames: another
// sequence's frames join the saved desk's map, a saved map never recognised leaves the run's own
// map, and what is refused. Threads: the loop closer joins the saved map while tracking and fusion
// read its corrections (run under ThreadSanitizer). The synthetic room's case is in
// test_sessions_room.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>

#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "session_runs.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

using test::kRpy;
using test::kXyz;

Trajectory graphOf(const std::string& session) { return graphTrajectory(readSession(session)); }

// Whether every pose of `part` (by timestamp) is in `whole`.
bool holdsEvery(const Trajectory& whole, const Trajectory& part) {
  std::set<double> stamps;
  for (const StampedPose& p : whole.poses()) stamps.insert(p.timestamp);
  for (const StampedPose& p : part.poses())
    if (!stamps.count(p.timestamp)) return false;
  return true;
}

TEST(Continuation, RealFramesOfAnotherSequenceJoinTheSavedDesksMap) {
  // fr1/xyz looks at the desk fr1/rpy was mapped from; both have the motion capture's poses in
  // one frame, so the continued session's keyframes, old and new, are scored in one alignment.
  const std::string dir = test::freshDir();
  const std::string map = test::sharedMap(kRpy, test::tumDir(kRpy));
  const std::string map_before = test::digest(map + ".pcd");
  const std::string session_before = test::digest(map + ".session");
  const test::SessionRun run =
      test::continueFrom(test::tumDir(kXyz), map + ".session", dir + "/more");
  ASSERT_EQ(run.code, 0) << run.log;
  EXPECT_NE(run.log.find("continuing: keyframe"), std::string::npos) << run.log;
  EXPECT_LE(test::jsonNumber(run.stats, "frames_unplaced"), 15) << run.stats;
  // The saved map stays as it was; the continued one is written beside the new name.
  EXPECT_EQ(test::digest(map + ".pcd"), map_before);
  EXPECT_EQ(test::digest(map + ".session"), session_before);

  const Trajectory saved = graphOf(map + ".session");
  const Trajectory both = graphOf(dir + "/more.session");
  ASSERT_GT(both.size(), saved.size()) << run.log;
  const Trajectory truth = test::merged(Trajectory::load(test::tumDir(kRpy) + "/groundtruth.txt"),
                                        Trajectory::load(test::tumDir(kXyz) + "/groundtruth.txt"));
  const double alone = absoluteTrajectoryError(saved, truth).translation.rmse;
  const double together = absoluteTrajectoryError(both, truth).translation.rmse;
  // One surface where they overlap: no more points than both runs' keyframes fused into one
  // TSDF offline (rgbdmap merge), plus 10%.
  const std::string xyz = test::sharedMap(kXyz, test::tumDir(kXyz));
  const std::size_t points = test::loadMap(dir + "/more.pcd").size();
  const std::size_t merged =
      test::mergedPoints(map + ".session", xyz + ".session", dir + "/merged.pcd");
  std::cout << "fr1/xyz continuing fr1/rpy's map: "
            << test::jsonNumber(run.stats, "frames_unplaced")
            << " frames before recognition; graph ATE " << together * 100
            << " cm (the saved keyframes alone " << alone * 100 << " cm); " << points
            << " points, merged offline " << merged << "\n";
  EXPECT_LT(together, alone + 0.005);
  EXPECT_LT(together, 0.035);
  EXPECT_GT(points, test::loadMap(map + ".pcd").size());
  EXPECT_LE(static_cast<double>(points), 1.1 * static_cast<double>(merged));
  // One graph: the saved keyframes are not held where the saved run left them (only its first
  // keyframe is), so the loops between the runs move them too.
  const Session saved_session = readSession(map + ".session");
  const Session continued = readSession(dir + "/more.session");
  double moved = 0.0;
  for (std::size_t id = 0; id < saved_session.graph.keyframes.size(); ++id)
    moved = std::max(moved, (saved_session.graph.keyframes[id].pose.translation() -
                             continued.graph.keyframes[id].pose.translation())
                                .norm());
  EXPECT_EQ(saved_session.graph.keyframes[0].pose.matrix(),
            continued.graph.keyframes[0].pose.matrix());
  EXPECT_GT(moved, 1e-6);
  // One trajectory for the whole map: every frame and keyframe of both runs, at the final poses.
  // (fr1/xyz was recorded before fr1/rpy, whose poses come first: read in time order.)
  const Trajectory frames = Trajectory::load(dir + "/more_trajectory.txt");
  const Trajectory keyframes = Trajectory::load(dir + "/more_keyframes.txt");
  EXPECT_TRUE(holdsEvery(frames, Trajectory::load(map + "_trajectory.txt")));
  EXPECT_TRUE(holdsEvery(keyframes, Trajectory::load(map + "_keyframes.txt")));
  EXPECT_EQ(frames.size(), continued.frames.size());
  EXPECT_EQ(keyframes.size(), continued.fused.size());
  const double every_frame = absoluteTrajectoryError(frames, truth).translation.rmse;
  std::cout << "both runs' " << frames.size() << " frames: ATE " << every_frame * 100 << " cm\n";
  EXPECT_LT(every_frame, 0.035);
  // The continued session continues again: it reads back whole.
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " session " + dir + "/more.session", &output), 0) << output;
}

TEST(Continuation, ASavedMapNeverRecognisedLeavesTheRunsOwnMap) {
  // fr1/rpy's desk, and frames of the synthetic room it has never seen.
  const std::string dir = test::freshDir();
  const std::string map = test::sharedMap(kRpy, test::tumDir(kRpy));
  const std::string orbit = test::sharedSynthetic("orbit_40", " --frames 40");
  // A checkpoint with every keyframe: none may write a session while the run is on its own.
  const test::SessionRun run =
      test::continueFrom(orbit, map + ".session", dir + "/more",
                         "--set checkpoint.every_keyframes=1 --set checkpoint.min_seconds=0");
  EXPECT_EQ(run.code, 1) << run.log;
  EXPECT_GE(test::countOccurrences(run.log, "checkpoint: "), 3u) << run.log;
  EXPECT_NE(run.log.find("the saved map was never recognised"), std::string::npos) << run.log;
  EXPECT_GT(test::jsonNumber(run.stats, "keyframes_looked_for"), 0) << run.stats;
  EXPECT_EQ(test::jsonNumber(run.stats, "frames_unplaced"),
            test::jsonNumber(run.stats, "frames_processed"));
  // Its own map, in its own frame, as a run from nothing gives it; no session of two frames.
  EXPECT_FALSE(fs::exists(dir + "/more.session"));
  const std::string alone_map = test::sharedMap("orbit_40", orbit);
  const double own = static_cast<double>(test::loadMap(dir + "/more.pcd").size());
  const double alone = static_cast<double>(test::loadMap(alone_map + ".pcd").size());
  EXPECT_NEAR(own, alone, 0.01 * alone);
  // Its trajectory holds its own frames only: the saved run's are in a frame it never joined.
  EXPECT_EQ(run.trajectory.size(), Trajectory::load(alone_map + "_trajectory.txt").size());
  // Where it is: the same surfaces, as precise as the run from nothing.
  EXPECT_NEAR(test::precisionOf(dir + "/more.pcd", orbit, dir + "/more_keyframes.txt"),
              test::precisionOf(alone_map + ".pcd", orbit, alone_map + "_keyframes.txt"), 0.005);
}

// Kept keyframes beyond their memory budget go to a scratch file, and a checkpoint's session,
// written on its own thread while fusion goes on appending to that file, reads them back: the
// session holds every kept keyframe, those on disk too, and reads back whole.
TEST(Continuation, ASessionHoldsTheKeptKeyframesThatWentToDisk) {
  const std::string dir = test::freshDir();
  // fr1/rpy's first 50 frames: 17 keyframes, 12 of them on disk (release), half the frames of
  // the whole excerpt under ThreadSanitizer.
  const std::string frames = test::sequenceSlice(test::tumDir(kRpy), 0, 50, dir + "/rpy50");
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + frames + " --out " + dir +
                          "/map.pcd --rate max --no-render --viewer none --set "
                          "pose.source=odometry --set loop.keyframe_memory=1 --set "
                          "checkpoint.every_keyframes=1 --set checkpoint.min_seconds=0 --stats " +
                          dir + "/map.json",
                      &output),
            0)
      << output;
  const std::string stats = test::readFile(dir + "/map.json");
  const double on_disk = test::jsonNumber(stats, "kept_keyframes_on_disk");
  EXPECT_GT(on_disk, 5) << stats;
  EXPECT_GE(test::countOccurrences(output, "session: "), 3u) << output;
  const Session session = readSession(dir + "/map.session");
  EXPECT_GT(static_cast<double>(session.keyframes.size()), on_disk) << stats;
  for (const KeyframeStore::Entry& e : session.keyframes) {
    ASSERT_TRUE(e.depth_png && e.colour_png);
    EXPECT_GT(e.depth_png->size(), 1000u);
    EXPECT_GT(e.colour_png->size(), 1000u);
  }
  EXPECT_EQ(test::run(test::binary() + " session " + dir + "/map.session", &output), 0) << output;
}

TEST(Continuation, RefusesWhatCannotGoOnFromASession) {
  const std::string dir = test::freshDir();
  // A copy: a refusal that failed would write beside it.
  test::copyMap(test::sharedMap(kXyz, test::tumDir(kXyz)), dir, "map");
  const std::string before = test::digest(dir + "/map.pcd");
  const std::string cli = test::binary() + " --source tum:" + test::tumDir(kXyz) +
                          " --no-render --viewer none --continue " + dir;
  std::string output;
  EXPECT_EQ(test::run(cli + "/map.session --out " + dir + "/map.pcd", &output), 2);
  EXPECT_NE(output.find("would be written beside the saved map"), std::string::npos) << output;
  EXPECT_EQ(test::digest(dir + "/map.pcd"), before);
  EXPECT_EQ(
      test::run(cli + "/map.session --out " + dir + "/b.pcd --octomap " + dir + "/b.bt", &output),
      2);
  EXPECT_NE(output.find("keeps no free space"), std::string::npos) << output;
  EXPECT_EQ(
      test::run(cli + "/map.session --out " + dir + "/b.pcd --set loop.enabled=false", &output), 2);
  EXPECT_NE(output.find("loop.enabled=false"), std::string::npos) << output;
  EXPECT_EQ(test::run(cli + "/missing.session --out " + dir + "/b.pcd", &output), 2);
  EXPECT_NE(output.find(dir + "/missing.session"), std::string::npos) << output;
  EXPECT_NE(
      test::run(cli + "/map.session --localise " + dir + "/map.session --out " + dir + "/b.pcd",
                &output),
      0);
  EXPECT_NE(output.find("excludes"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir + "/b.pcd"));
}

}  // namespace
}  // namespace rgbdmap
