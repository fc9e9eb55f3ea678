// Localisation in a saved map (--localise MAP.session): a second run's frames are posed in the
// first run's frame, nothing is mapped, and the saved map and session stay as they were.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

const std::string kRpy = "rgbd_dataset_freiburg1_rpy_head100";
const std::string kXyz = "rgbd_dataset_freiburg1_xyz";
// One lap round the 5x4 m room (seed 1), and another lap (seed 2) 15 cm further from the walls,
// whose second half starts on the far side of the room from the first run's start.
const std::string kFirstWalk = " --path walk --frames 360 --seed 1";
const std::string kSecondWalk = " --path walk --frames 360 --seed 2 --path-inset 0.95";

// A copy of `sequence` holding only its frames from `first` on (lists cut, images linked).
std::string tailOf(const std::string& sequence, std::size_t first, const std::string& target) {
  fs::create_directories(target);
  for (const char* list : {"rgb.txt", "depth.txt"}) {
    std::ifstream in(sequence + "/" + list);
    std::ofstream out(target + "/" + list);
    std::size_t frame = 0;
    for (std::string line; std::getline(in, line);)
      if (line.empty() || line[0] == '#' || frame++ >= first) out << line << "\n";
  }
  fs::copy_file(sequence + "/groundtruth.txt", target + "/groundtruth.txt");
  for (const char* folder : {"rgb", "depth"})
    fs::create_directory_symlink(sequence + "/" + folder, target + "/" + folder);
  return target;
}

// Maps `sequence` with odometry and loop closure into dir/map.pcd (and dir/map.session).
void mapInto(const std::string& sequence, const std::string& dir) {
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + sequence + " --out " + dir +
                          "/map.pcd --no-render --viewer none --set pose.source=odometry",
                      &output),
            0)
      << output;
  ASSERT_TRUE(fs::is_directory(dir + "/map.session")) << output;
}

struct Localised {
  int code = 0;
  std::string log, stats;
  Trajectory trajectory;
};

Localised localise(const std::string& sequence, const std::string& session, const std::string& out,
                   const std::string& extra = "") {
  Localised run;
  run.code = test::run(test::binary() + " --source tum:" + sequence + " --localise " + session +
                           " --out " + out + ".pcd --no-render --viewer none --stats " + out +
                           ".json" + extra,
                       &run.log);
  run.stats = test::readFile(out + ".json");
  // The statistics are JSON a reader takes (a separator once went missing between two entries).
  EXPECT_EQ(
      test::run("python3 -c 'import json, sys; json.load(open(sys.argv[1]))' " + out + ".json"), 0)
      << run.stats;
  if (fs::exists(out + "_trajectory.txt"))
    run.trajectory = Trajectory::load(out + "_trajectory.txt");
  return run;
}

// Position errors of `localised` against its sequence's truth, in the frame the saved run's
// keyframes align to their own truth in: one alignment, made without the localised frames.
std::vector<double> errorsInTheSavedFrame(const std::string& saved_keyframes,
                                          const std::string& saved_truth,
                                          const Trajectory& localised,
                                          const std::string& localised_truth) {
  const Eigen::Isometry3d saved_to_world =
      absoluteTrajectoryError(Trajectory::load(saved_keyframes), Trajectory::load(saved_truth))
          .alignment;
  const Trajectory truth = Trajectory::load(localised_truth);
  std::vector<double> errors;
  for (const StampedPose& p : localised.poses()) {
    const auto true_pose = truth.interpolate(p.timestamp);
    if (true_pose)
      errors.push_back(((saved_to_world * p.pose).translation() - true_pose->translation()).norm());
  }
  return errors;
}

std::string digest(const std::string& path) {
  std::string all;
  if (fs::is_directory(path)) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(path)) names.push_back(entry.path().string());
    std::sort(names.begin(), names.end());
    for (const std::string& name : names) all += name + "\n" + test::readFile(name);
  } else {
    all = test::readFile(path);
  }
  return all;
}

TEST(Localisation, ASecondWalkIsPosedInTheFirstRunsFrameAndTheSavedMapStaysAsItWas) {
  const std::string dir = test::freshDir();
  const std::string first = test::sharedSynthetic("walk_lap_seed1", kFirstWalk);
  const std::string second =
      tailOf(test::sharedSynthetic("walk_lap_seed2", kSecondWalk), 180, dir + "/second");
  mapInto(first, dir);
  const std::string map_before = digest(dir + "/map.pcd");
  const std::string session_before = digest(dir + "/map.session");

  const Localised run = localise(second, dir + "/map.session", dir + "/localised");
  ASSERT_EQ(run.code, 0) << run.log;
  EXPECT_NE(run.log.find("localisation: placed in the saved map at keyframe"), std::string::npos)
      << run.log;
  // Every frame has its pose; those before the saved map was recognised are counted (a few).
  EXPECT_EQ(run.trajectory.size(), 180u) << run.log;
  const double unplaced = test::jsonNumber(run.stats, "frames_unplaced");
  EXPECT_LE(unplaced, 30) << run.log;
  const std::vector<double> errors =
      errorsInTheSavedFrame(dir + "/map_keyframes.txt", first + "/groundtruth.txt", run.trajectory,
                            second + "/groundtruth.txt");
  ASSERT_EQ(errors.size(), 180u);
  const ErrorStatistics e = errorStatistics(errors);
  std::cout << "localised in the saved map: " << errors.size() << " frames, " << unplaced
            << " before recognition; error median " << e.median * 100 << " cm, rmse "
            << e.rmse * 100 << " cm, max " << e.max * 100 << " cm\n";
  EXPECT_LT(e.median, 0.02);
  EXPECT_LT(e.max, 0.06);

  // Nothing mapped, nothing of the saved run's changed.
  EXPECT_FALSE(fs::exists(dir + "/localised.pcd"));
  EXPECT_FALSE(fs::exists(dir + "/localised.session"));
  EXPECT_EQ(digest(dir + "/map.pcd"), map_before);
  EXPECT_EQ(digest(dir + "/map.session"), session_before);
}

// `a` and `b` merged in time order.
Trajectory merged(const Trajectory& a, const Trajectory& b) {
  std::vector<StampedPose> poses = a.poses();
  poses.insert(poses.end(), b.poses().begin(), b.poses().end());
  std::sort(poses.begin(), poses.end(),
            [](const StampedPose& x, const StampedPose& y) { return x.timestamp < y.timestamp; });
  return Trajectory(std::move(poses));
}

TEST(Localisation, RealFramesOfAnotherSequenceArePosedInTheSavedDesksFrame) {
  // fr1/xyz looks at the desk fr1/rpy was mapped from; both have the motion capture's poses in
  // one frame, so the saved keyframes and the localised frames are scored in one alignment.
  const std::string dir = test::freshDir();
  mapInto(test::tumDir(kRpy), dir);
  const Localised run = localise(test::tumDir(kXyz), dir + "/map.session", dir + "/localised");
  ASSERT_EQ(run.code, 0) << run.log;
  ASSERT_EQ(run.trajectory.size(), 32u) << run.log;  // fr1/xyz's 37 frames, 32 associated
  const Trajectory saved = Trajectory::load(dir + "/map_keyframes.txt");
  const Trajectory saved_truth = Trajectory::load(test::tumDir(kRpy) + "/groundtruth.txt");
  const Trajectory truth =
      merged(saved_truth, Trajectory::load(test::tumDir(kXyz) + "/groundtruth.txt"));
  const double alone = absoluteTrajectoryError(saved, saved_truth).translation.rmse;
  const double together =
      absoluteTrajectoryError(merged(saved, run.trajectory), truth).translation.rmse;
  std::cout << "fr1/xyz localised in fr1/rpy's map: ATE " << together * 100
            << " cm with the saved keyframes (those alone " << alone * 100 << " cm); "
            << test::jsonNumber(run.stats, "frames_unplaced") << " frames before recognition\n";
  // Frames placed a few centimetres off would raise the ATE of the whole.
  EXPECT_LT(together, alone + 0.005);
  EXPECT_LT(together, 0.035);
  EXPECT_LE(test::jsonNumber(run.stats, "frames_unplaced"), 15);
}

TEST(Localisation, ASavedMapNeverRecognisedIsSaidAndFails) {
  // The synthetic room's session, and real frames of a desk it has never seen.
  const std::string dir = test::freshDir();
  mapInto(test::sharedSynthetic("walk_lap_seed1", kFirstWalk), dir);
  const Localised run = localise(test::tumDir(kXyz), dir + "/map.session", dir + "/localised");
  EXPECT_EQ(run.code, 1) << run.log;
  EXPECT_NE(run.log.find("the saved map was never recognised"), std::string::npos) << run.log;
  EXPECT_EQ(test::jsonNumber(run.stats, "frames_unplaced"),
            test::jsonNumber(run.stats, "frames_processed"));
}

TEST(Localisation, RefusesToWriteBesideTheSavedMapOrToMap) {
  const std::string dir = test::freshDir();
  mapInto(test::tumDir(kXyz), dir);
  const std::string before = digest(dir + "/map_trajectory.txt");
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --localise " +
                          dir + "/map.session/ --out " + dir + "/map.pcd --no-render --viewer none",
                      &output),
            2);
  EXPECT_NE(output.find("would be written beside the saved map"), std::string::npos) << output;
  EXPECT_EQ(digest(dir + "/map_trajectory.txt"), before);
  EXPECT_EQ(test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --localise " +
                          dir + "/map.session --out " + dir +
                          "/other.pcd --grid g.pgm --no-render --viewer none",
                      &output),
            2);
  EXPECT_NE(output.find("nothing is mapped while localising"), std::string::npos) << output;
  EXPECT_EQ(
      test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --localise " + dir +
                    "/missing.session --out " + dir + "/other.pcd --no-render --viewer none",
                &output),
      2);
  EXPECT_NE(output.find(dir + "/missing.session"), std::string::npos) << output;
}

}  // namespace
}  // namespace rgbdmap
