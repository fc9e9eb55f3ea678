// The session saved beside the map (MAP.session/): what it holds is what the run had, it reads
// back whole, and a truncated, corrupt or other-version session is refused naming the file.

#include <gtest/gtest.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "session_runs.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

using test::kRpy;

// The folder of fr1/rpy's 100 frames mapped with odometry and loop closure (the default for a
// camera) into map.pcd, map.session...: shared by the tests and processes (test::sharedMap), read
// only.
std::string mappedRun() {
  return fs::path(test::sharedMap(kRpy, test::tumDir(kRpy))).parent_path().string();
}

std::size_t lines(const std::string& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') ++n;
  return n;
}

// A copy of the run's session in `dir` (the test's freshDir()).
std::string copySession(const std::string& dir, const std::string& name) {
  const std::string copy = dir + "/" + name;
  fs::copy(mappedRun() + "/map.session", copy);
  return copy;
}

// The message readSession refuses `path` with ("" when it reads).
std::string refusal(const std::string& path) {
  try {
    readSession(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SessionFile, HoldsTheRunsGraphPlacesAndKeyframeImages) {
  const std::string dir = mappedRun();
  ASSERT_TRUE(fs::is_directory(dir + "/map.session")) << test::readFile(dir + "/map_log.txt");
  EXPECT_NE(test::readFile(dir + "/map_log.txt").find("session: "), std::string::npos);
  const Session session = readSession(dir + "/map.session");
  // Every fused keyframe kept (100 frames are within the budget), as the keyframe file says.
  EXPECT_EQ(session.keyframes.size(), lines(dir + "/map_keyframes.txt"));
  ASSERT_GE(session.graph.keyframes.size(), 5u);
  // No loop here: each keyframe's odometry edge, and the local window's to earlier keyframes.
  std::vector<int> tied(session.graph.keyframes.size(), 0);
  for (const PoseGraph::Edge& e : session.graph.edges) {
    EXPECT_FALSE(e.loop);
    ASSERT_LT(e.from, e.to);
    ++tied[static_cast<std::size_t>(e.to)];
  }
  EXPECT_EQ(tied.front(), 0);
  for (std::size_t i = 1; i < tied.size(); ++i) EXPECT_GE(tied[i], 1) << "keyframe " << i;
  EXPECT_GT(session.graph.edges.size(), session.graph.keyframes.size() - 1);
  EXPECT_EQ(session.graph.places.size(), session.graph.keyframes.size());
  ASSERT_TRUE(session.graph.places.front());
  EXPECT_GT(session.graph.places.front()->view.points.size(), 100u);
  EXPECT_EQ(session.graph.places.front()->view.descriptors.rows,
            static_cast<int>(session.graph.places.front()->view.points.size()));
  EXPECT_FALSE(session.graph.places.front()->reference.levels.empty());
  EXPECT_DOUBLE_EQ(session.camera.fx, 517.3);
  EXPECT_DOUBLE_EQ(session.camera.cy, 255.3);
  EXPECT_NE(session.configuration.find("pose:"), std::string::npos);
  for (std::size_t i = 1; i < session.graph.keyframes.size(); ++i)
    EXPECT_GT(session.graph.keyframes[i].timestamp, session.graph.keyframes[i - 1].timestamp);

  // A kept keyframe's depth is the sensor's, to the inverse-depth step.
  const TumSequence sequence(test::tumDir(kRpy));
  const KeyframeStore::Entry& kept = session.keyframes[session.keyframes.size() / 2];
  std::size_t j = 0;
  while (j < sequence.size() && std::abs(sequence[j].rgb_time - kept.timestamp) > 1e-6) ++j;
  ASSERT_LT(j, sequence.size()) << "no frame at " << kept.timestamp;
  const cv::Mat units = cv::imdecode(*kept.depth_png, cv::IMREAD_UNCHANGED);
  const cv::Mat truth = cv::imread(sequence[j].depth_path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(units.type(), CV_16UC1);
  ASSERT_EQ(units.size(), truth.size());
  std::size_t compared = 0, within = 0;
  for (int y = 0; y < truth.rows; y += 4)
    for (int x = 0; x < truth.cols; x += 4) {
      const double z = truth.at<std::uint16_t>(y, x) / 5000.0;
      const int u = units.at<std::uint16_t>(y, x);
      if (z < 0.5 || z > 4.0 || u == 0) continue;
      ++compared;
      const double kept_z = KeyframeStore::kInverseDepthUnits / u;
      within += std::abs(kept_z - z) <= z * z / KeyframeStore::kInverseDepthUnits + 1e-3;
    }
  ASSERT_GT(compared, 5000u);
  EXPECT_GE(static_cast<double>(within), 0.99 * compared);

  // The run's trajectories, as tracked with their anchors: at the graph's poses they are the
  // files the run wrote beside its map (a run that continues the session writes them again).
  for (const auto& [poses, file] : {std::make_pair(&session.frames, "/map_trajectory.txt"),
                                    std::make_pair(&session.fused, "/map_keyframes.txt")}) {
    const Trajectory written = Trajectory::load(dir + file);
    const Trajectory resolved = resolvedTrajectory(session, *poses);
    ASSERT_EQ(resolved.size(), written.size()) << file;
    ASSERT_GT(resolved.size(), 4u) << file;
    for (std::size_t i = 0; i < resolved.size(); ++i) {
      EXPECT_NEAR(resolved[i].timestamp, written[i].timestamp, 1e-6) << file;
      EXPECT_LT((resolved[i].pose.translation() - written[i].pose.translation()).norm(), 1e-6)
          << file;
    }
  }
  EXPECT_EQ(session.frames.size(), lines(dir + "/map_trajectory.txt"));
}

TEST(SessionFile, ReadAndWrittenAgainGivesTheSameFiles) {
  const std::string original = mappedRun() + "/map.session";
  const std::string again = test::freshDir() + "/again.session";
  std::string error;
  ASSERT_TRUE(writeSession(readSession(original), again, error)) << error;
  for (const char* name :
       {"graph.bin", "places.bin", "keyframes.bin", "images.bin", "places.data", "config.yaml"})
    EXPECT_EQ(test::readFile(original + "/" + name), test::readFile(again + "/" + name)) << name;
  // (The trajectories' quaternions are normalised when read: the last digit may change.)
  for (const char* name : {"frames.anchored", "keyframes.anchored"}) {
    EXPECT_GT(lines(original + "/" + name), 4u) << name;
    EXPECT_EQ(lines(original + "/" + name), lines(again + "/" + name)) << name;
  }
  // Written over: the new folder takes the old one's place, nothing is left beside it.
  ASSERT_TRUE(writeSession(readSession(original), again, error)) << error;
  std::size_t beside = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(again).parent_path()))
    beside += entry.path() != fs::path(again);
  EXPECT_EQ(beside, 0u);
  EXPECT_EQ(refusal(again), "");
}

// A run's sessions (a checkpoint's, then the next): the next links the images and places the one
// before wrote and appends only the new keyframes' images (its places are the same); each reads
// back whole.
TEST(SessionFile, ARunsNextSessionAddsOnlyTheNewKeyframesImages) {
  Session whole = readSession(mappedRun() + "/map.session");
  ASSERT_GT(whole.keyframes.size(), 6u);
  std::uint64_t id = 100;  // as the run's keyframe store numbers them
  for (KeyframeStore::Entry& e : whole.keyframes) e.id = id++;
  Session first = whole;
  first.keyframes.resize(whole.keyframes.size() / 2);
  // The second lets two of the first's keyframes go (a budget), as a run may.
  Session second = whole;
  second.keyframes.erase(second.keyframes.begin() + 1, second.keyframes.begin() + 3);
  const auto imageBytes = [](const std::vector<KeyframeStore::Entry>& keyframes, std::size_t from) {
    std::uint64_t bytes = 0;
    for (std::size_t i = from; i < keyframes.size(); ++i) bytes += keyframes[i].imageBytes();
    return bytes;
  };

  const std::string dir = test::freshDir();
  const std::string path = dir + "/run.session";
  SessionAppends appends;
  std::string error;
  ASSERT_TRUE(writeSession(first, path, error, nullptr, &appends)) << error;
  const std::uint64_t places = fs::file_size(path + "/places.data");
  EXPECT_GT(places, 0u);
  EXPECT_EQ(appends.appended, imageBytes(first.keyframes, 0) + places);
  ASSERT_TRUE(writeSession(second, path, error, nullptr, &appends)) << error;
  EXPECT_EQ(appends.appended, imageBytes(whole.keyframes, first.keyframes.size()));
  EXPECT_EQ(fs::file_size(path + "/images.bin"), imageBytes(whole.keyframes, 0));
  EXPECT_EQ(fs::file_size(path + "/places.data"), places);
  for (const char* name : {"/images.bin", "/places.data"})
    EXPECT_EQ(fs::hard_link_count(path + name), 1u) << name << ": the earlier folder is gone";

  const Session read = readSession(path);
  ASSERT_EQ(read.keyframes.size(), second.keyframes.size());
  ASSERT_EQ(read.graph.places.size(), second.graph.places.size());
  for (std::size_t i = 0; i < read.graph.places.size(); ++i) {
    ASSERT_EQ(!read.graph.places[i], !second.graph.places[i]) << i;
    if (read.graph.places[i]) {
      EXPECT_EQ(read.graph.places[i]->view.points.size(),
                second.graph.places[i]->view.points.size());
    }
  }
  for (std::size_t i = 0; i < read.keyframes.size(); ++i) {
    EXPECT_EQ(read.keyframes[i].timestamp, second.keyframes[i].timestamp);
    EXPECT_EQ(*read.keyframes[i].depth_png, *second.keyframes[i].depth_png);
    EXPECT_EQ(*read.keyframes[i].colour_png, *second.keyframes[i].colour_png);
  }
  // Another session's log, or none: the images are written whole.
  const std::string other = dir + "/other.session";
  ASSERT_TRUE(writeSession(second, other, error, nullptr, &appends)) << error;
  EXPECT_EQ(appends.appended, imageBytes(second.keyframes, 0) + places);
  EXPECT_EQ(fs::file_size(other + "/images.bin"), imageBytes(second.keyframes, 0));
}

// A checkpoint taken while the loop closer still has the newest keyframes queued: kept keyframes
// anchored beyond its graph, fewer places than keyframes. Such a session is whole, and reads.
TEST(SessionFile, ASessionSavedWhileLoopClosureLagsReads) {
  Session lagging = readSession(mappedRun() + "/map.session");
  const std::size_t graph = lagging.graph.keyframes.size() - 3;
  lagging.graph.keyframes.resize(graph);
  std::vector<PoseGraph::Edge> edges;
  for (const PoseGraph::Edge& e : lagging.graph.edges)
    if (static_cast<std::size_t>(std::max(e.from, e.to)) < graph) edges.push_back(e);
  lagging.graph.edges = edges;
  lagging.graph.places.resize(graph - 2);
  ASSERT_GT(lagging.keyframes.back().anchor, static_cast<std::int64_t>(graph));
  const std::string path = test::freshDir() + "/lagging.session";
  std::string error;
  ASSERT_TRUE(writeSession(lagging, path, error)) << error;
  const Session read = readSession(path);
  EXPECT_EQ(read.graph.keyframes.size(), graph);
  EXPECT_EQ(read.graph.places.size(), graph);  // the newest without a place
  EXPECT_FALSE(read.graph.places.back());
  EXPECT_EQ(read.keyframes.size(), lagging.keyframes.size());
  EXPECT_EQ(read.keyframes.back().anchor, lagging.keyframes.back().anchor);
}

TEST(SessionFile, TruncatedCorruptOrOtherVersionIsRefusedNamingTheFile) {
  const std::string dir = test::freshDir();
  {
    const std::string s = copySession(dir, "truncated.session");
    fs::resize_file(s + "/keyframes.bin", fs::file_size(s + "/keyframes.bin") / 2);
    const std::string message = refusal(s);
    EXPECT_NE(message.find(s + "/keyframes.bin: truncated"), std::string::npos) << message;
  }
  {
    const std::string s = copySession(dir, "corrupt.session");
    std::fstream file(s + "/places.bin", std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(static_cast<std::streamoff>(fs::file_size(s + "/places.bin") / 2));
    file.put('\x5a');
    file.close();
    const std::string message = refusal(s);
    EXPECT_NE(message.find(s + "/places.bin: corrupt"), std::string::npos) << message;
  }
  {
    const std::string s = copySession(dir, "version.session");
    std::string summary = test::readFile(s + "/session.yaml");
    summary.replace(summary.find("version: 1"), 10, "version: 9");
    std::ofstream(s + "/session.yaml") << summary;
    const std::string message = refusal(s);
    EXPECT_NE(message.find(s + "/session.yaml: session format version 9"), std::string::npos)
        << message;
  }
  {
    const std::string s = copySession(dir, "trajectory.session");
    std::string frames = test::readFile(s + "/frames.anchored");
    frames.insert(frames.find('\n') + 1, "1305031102.1 0 0 nan 0 0 0 1 3\n");
    std::ofstream(s + "/frames.anchored") << frames;
    EXPECT_NE(refusal(s).find(s + "/frames.anchored: line 2: corrupt"), std::string::npos)
        << refusal(s);
  }
  {
    // A session written before the trajectories were kept reads, without them.
    const std::string s = copySession(dir, "older.session");
    fs::remove(s + "/frames.anchored");
    fs::remove(s + "/keyframes.anchored");
    EXPECT_EQ(refusal(s), "");
    EXPECT_TRUE(readSession(s).frames.empty());
  }
  {
    const std::string s = copySession(dir, "missing.session");
    fs::remove(s + "/graph.bin");
    EXPECT_NE(refusal(s).find(s + "/graph.bin: cannot open"), std::string::npos) << refusal(s);
  }
  {
    // A file of another kind in a session's place.
    const std::string s = copySession(dir, "swapped.session");
    fs::copy_file(s + "/places.bin", s + "/graph.bin", fs::copy_options::overwrite_existing);
    EXPECT_NE(refusal(s).find(s + "/graph.bin: holds 'PLIX', expected 'GRPH'"), std::string::npos)
        << refusal(s);
  }
  {
    // The files only ever appended to: cut short, or a place changed.
    const std::string s = copySession(dir, "appended.session");
    fs::resize_file(s + "/images.bin", fs::file_size(s + "/images.bin") / 2);
    EXPECT_NE(refusal(s).find(s + "/images.bin: truncated"), std::string::npos) << refusal(s);
    const std::string t = copySession(dir, "places.session");
    fs::resize_file(t + "/places.data", fs::file_size(t + "/places.data") - 1);
    EXPECT_NE(refusal(t).find(t + "/places.data: truncated"), std::string::npos) << refusal(t);
    const std::string u = copySession(dir, "place.session");
    std::fstream file(u + "/places.data", std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(100);
    file.put('\x5a');
    file.close();
    EXPECT_NE(refusal(u).find(u + "/places.data (the place at byte 0): corrupt"), std::string::npos)
        << refusal(u);
  }
  // The command line: one message naming the file, exit 2.
  const std::string s = copySession(dir, "cli.session");
  fs::resize_file(s + "/graph.bin", 40);
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " session " + s, &output), 2);
  EXPECT_NE(output.find(s + "/graph.bin: truncated"), std::string::npos) << output;
  EXPECT_EQ(test::run(test::binary() + " session " + mappedRun() + "/map.session", &output), 0);
  EXPECT_NE(output.find("rgbdmap session, format version 1"), std::string::npos) << output;
}

// The session holds the map in the form fusion goes on from: its kept keyframes fused at the
// graph's poses give back the map the run wrote.
TEST(SessionFile, ItsKeyframesFusedAgainGiveTheMapTheRunWrote) {
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " session " + mappedRun() + "/map.session --map " + dir +
                          "/again.pcd",
                      &output),
            0)
      << output;
  const MapCloud written = test::loadMap(mappedRun() + "/map.pcd");
  const MapCloud again = test::loadMap(dir + "/again.pcd");
  ASSERT_GT(written.size(), 100000u);
  EXPECT_NEAR(static_cast<double>(again.size()), static_cast<double>(written.size()),
              0.01 * written.size());
  pcl::KdTreeFLANN<MapCloud::PointType> tree;
  tree.setInputCloud(written.makeShared());
  std::vector<int> index(1);
  std::vector<float> squared(1);
  std::size_t near = 0, checked = 0;
  // Within a voxel (1 cm): the kept images are quantised (inverse depth in steps of half the
  // sensor's noise), as for the mapper's own re-fusion, so the surface moves by a millimetre or
  // two and a few fringe voxels (seen once) come and go. Measured 96.9%.
  for (std::size_t i = 0; i < again.size(); i += 7, ++checked)
    if (tree.nearestKSearch(again[i], 1, index, squared) == 1 && squared[0] <= 1e-4f) ++near;
  EXPECT_GE(static_cast<double>(near), 0.95 * checked) << near << " of " << checked;
}

// A session saved before tracking.undistort and filter.undistort became one key still loads: its
// configuration is read with one warning line naming the file and the key now.
TEST(SessionFile, ItsConfigurationWithTheFormerUndistortKeysStillLoads) {
  const std::string dir = test::freshDir();
  const std::string copy = copySession(dir, "old.session");
  const std::string config = copy + "/config.yaml";
  std::string text = test::readFile(config);
  const auto drop = text.find("  undistort: ");
  ASSERT_NE(drop, std::string::npos) << text;
  text.erase(drop, text.find('\n', drop) + 1 - drop);
  for (const std::string section : {"tracking:\n", "filter:\n"}) {
    const auto at = text.find("\n" + section);
    ASSERT_NE(at, std::string::npos) << text;
    text.insert(at + 1 + section.size(), "  undistort: true  # former key\n");
  }
  std::ofstream(config, std::ios::trunc) << text;
  std::string output;
  ASSERT_EQ(
      test::run(test::binary() + " session " + copy + " --map " + dir + "/again.pcd", &output), 0)
      << output;
  EXPECT_EQ(test::countOccurrences(output, "former names, still read"), 1u) << output;
  EXPECT_NE(
      output.find(config + ": tracking.undistort and filter.undistort are now camera.undistort"),
      std::string::npos)
      << output;
  EXPECT_GT(test::loadMap(dir + "/again.pcd").size(), 100000u);
}

TEST(SessionFile, NotSavedWhenTurnedOffOrWithoutLoopClosure) {
  const std::string dir = test::freshDir();
  // 20 frames, a few keyframes: a session would be written of them.
  const std::string frames = test::sequenceSlice(test::tumDir(kRpy), 0, 20, dir + "/rpy20");
  std::string output;
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + frames + " --out " + dir +
                          "/off.pcd --no-render --viewer none --set pose.source=odometry " +
                          "--set checkpoint.session=false",
                      &output),
            0)
      << output;
  EXPECT_FALSE(fs::exists(dir + "/off.session"));
  // Ground-truth poses: no loop closure, nothing a session is made of; the log says so.
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + frames + " --out " + dir +
                          "/truth.pcd --no-render --viewer none",
                      &output),
            0)
      << output;
  EXPECT_FALSE(fs::exists(dir + "/truth.session"));
  EXPECT_NE(output.find("session: not saved"), std::string::npos) << output;
}

}  // namespace
}  // namespace rgbdmap
