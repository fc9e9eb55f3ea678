#include "session_runs.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/sessions/session_stream.hpp"
#include "test_support.hpp"

namespace rgbdmap::test {

namespace fs = std::filesystem;

namespace {

// Maps as mapTo() says; `output` gets what the program printed.
void mapWith(const std::string& program, const std::string& sequence, const std::string& map,
             std::string& output) {
  ASSERT_EQ(run(program + " --source tum:" + sequence + " --out " + map +
                    " --rate max --no-render --viewer none --set pose.source=odometry",
                &output),
            0)
      << output;
  ASSERT_TRUE(fs::is_directory(sessionPathOf(map))) << output;
}

}  // namespace

void mapTo(const std::string& sequence, const std::string& map) {
  std::string output;
  mapWith(binary(), sequence, map, output);
}

std::string sharedMap(const std::string& name, const std::string& sequence) {
  const char* mapper = std::getenv("RGBDMAP_TEST_MAPPER");
  const std::string program = mapper && *mapper ? std::string(mapper) : binary();
  const std::string build =
      std::to_string(fs::last_write_time(program).time_since_epoch().count()) + "-" +
      std::to_string(fs::file_size(program));
  return writeOnce(sharedDir() + "/maps/" + name + "." + build,
                   [&](const std::string& folder) {
                     std::string output;
                     mapWith(program, sequence, folder + "/map.pcd", output);
                     std::ofstream(folder + "/map_log.txt") << output;
                   }) +
         "/map";
}

std::string copyMap(const std::string& prefix, const std::string& dir, const std::string& name) {
  const fs::path from = fs::path(prefix).parent_path();
  const std::string stem = fs::path(prefix).filename().string();
  for (const fs::directory_entry& entry : fs::directory_iterator(from)) {
    const std::string file = entry.path().filename().string();
    if (file.rfind(stem, 0) != 0) continue;
    fs::copy(entry.path(), fs::path(dir) / (name + file.substr(stem.size())),
             fs::copy_options::recursive);
  }
  return dir + "/" + name;
}

const Session& mappedSession(const std::string& tum_name) {
  static std::map<std::string, Session> sessions;
  const auto found = sessions.find(tum_name);
  if (found != sessions.end()) return found->second;
  const std::string map = sharedMap(tum_name, tumDir(tum_name));
  return sessions.emplace(tum_name, readSession(map + ".session")).first->second;
}

namespace {

SessionRun startFrom(const std::string& option, const std::string& sequence,
                     const std::string& session, const std::string& out,
                     const std::string& options = "") {
  SessionRun result;
  result.code =
      run(binary() + " --source tum:" + sequence + " " + option + " " + session + " --out " + out +
              ".pcd --rate max --no-render --viewer none --stats " + out + ".json " + options,
          &result.log);
  result.stats = readFile(out + ".json");
  // The statistics are JSON a reader takes (a separator once went missing between two entries).
  EXPECT_EQ(run("python3 -c 'import json, sys; json.load(open(sys.argv[1]))' " + out + ".json"), 0)
      << result.stats;
  if (fs::exists(out + "_trajectory.txt"))
    result.trajectory = loadAnyOrder(out + "_trajectory.txt");
  return result;
}

}  // namespace

SessionRun localise(const std::string& sequence, const std::string& session,
                    const std::string& out) {
  return startFrom("--localise", sequence, session, out);
}

Trajectory loadAnyOrder(const std::string& path) {
  std::ifstream in(path);
  std::vector<StampedPose> poses;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    StampedPose p;
    Eigen::Vector3d t;
    Eigen::Quaterniond q;
    fields >> p.timestamp >> t.x() >> t.y() >> t.z() >> q.x() >> q.y() >> q.z() >> q.w();
    EXPECT_TRUE(fields) << path << ": " << line;
    p.pose = Eigen::Isometry3d::Identity();
    p.pose.linear() = q.normalized().toRotationMatrix();
    p.pose.translation() = t;
    poses.push_back(p);
  }
  std::stable_sort(poses.begin(), poses.end(), [](const StampedPose& a, const StampedPose& b) {
    return a.timestamp < b.timestamp;
  });
  return Trajectory(std::move(poses));
}

SessionRun continueFrom(const std::string& sequence, const std::string& session,
                        const std::string& out, const std::string& options) {
  return startFrom("--continue", sequence, session, out, options);
}

std::string digest(const std::string& path) {
  if (!fs::is_directory(path)) return readFile(path);
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(path)) names.push_back(entry.path().string());
  std::sort(names.begin(), names.end());
  std::string all;
  for (const std::string& name : names) all += name + "\n" + readFile(name);
  return all;
}

Trajectory merged(const Trajectory& a, const Trajectory& b) {
  std::vector<StampedPose> poses = a.poses();
  poses.insert(poses.end(), b.poses().begin(), b.poses().end());
  std::sort(poses.begin(), poses.end(),
            [](const StampedPose& x, const StampedPose& y) { return x.timestamp < y.timestamp; });
  return Trajectory(std::move(poses));
}

std::optional<Eigen::Isometry3d> mergedTransformOf(const std::string& transforms,
                                                   const std::string& session) {
  std::ifstream in(transforms);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string name;
    double t[3], q[4];
    if (!(fields >> name) || name != session) continue;
    if (!(fields >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3])) return std::nullopt;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
    pose.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    return pose;
  }
  return std::nullopt;
}

MergeRun mergeSessions(const std::vector<std::string>& sessions, const std::string& out) {
  std::string command = binary() + " merge";
  for (const std::string& session : sessions) command += " " + session;
  MergeRun merge;
  merge.out = out;
  merge.code = run(command + " --out " + out, &merge.log);
  for (const std::string& session : sessions)
    merge.transforms.push_back(mergedTransformOf(stem(out) + "_transforms.txt", session));
  return merge;
}

void expectAllButOneJoined(const MergeRun& merge, const std::vector<std::string>& sessions,
                           std::size_t elsewhere) {
  ASSERT_EQ(merge.code, 0) << merge.log;
  EXPECT_NE(
      merge.log.find(sessions[elsewhere] + ": shares no place with the other sessions: left out"),
      std::string::npos)
      << merge.log;
  EXPECT_NE(merge.log.find("merged " + std::to_string(sessions.size() - 1) + " of " +
                           std::to_string(sessions.size()) + " sessions"),
            std::string::npos)
      << merge.log;
  for (std::size_t i = 0; i < sessions.size(); ++i)
    EXPECT_EQ(merge.transforms[i].has_value(), i != elsewhere) << sessions[i] << "\n" << merge.log;
  std::string output;
  EXPECT_EQ(run(binary() + " session " + sessionPathOf(merge.out), &output), 0) << output;
}

std::size_t mergedPoints(const std::string& first, const std::string& second,
                         const std::string& out) {
  const MergeRun merge = mergeSessions({first, second}, out);
  EXPECT_EQ(merge.code, 0) << merge.log;
  return fs::exists(out) ? loadMap(out).size() : 0;
}

std::vector<std::string> streamOf(const Session& saved, std::uint64_t run) {
  PoseCorrections corrections;
  RunStats stats;
  LoopCloser robot(saved.camera, TrackingOptions{}, LoopOptions{}, 0.3, 4.0, corrections, stats,
                   true, &saved.graph);
  SessionStream stream(run, saved.camera, SessionStream::Options{1e12, 1.0, 1e12});
  // The kept keyframes as the robot's map pieces.
  KeyframeStore decoder(0);
  Frame keyframe;
  for (const KeyframeStore::Entry& kept : saved.keyframes) {
    decoder.decode(kept, keyframe);
    stream.addKeyframe(keyframe);
  }
  std::vector<std::string> records;
  for (SessionStream::Record& r : stream.take(robot, 0.0)) records.push_back(std::move(r.bytes));
  return records;
}

std::size_t send(FleetMerger& merger, std::size_t robot, const Session& saved, std::uint64_t run,
                 const std::string& topic) {
  std::size_t gaps = 0;
  for (const std::string& record : streamOf(saved, run))
    gaps += merger.receive(robot, record, topic) == SessionAssembler::Result::kGap ? 1 : 0;
  return gaps;
}

Session streamed(const Session& saved) {
  SessionAssembler merger;
  for (const std::string& record : streamOf(saved, 1)) merger.apply(record, "test");
  return merger.session();
}

Eigen::Isometry3d frameInWorld(const std::string& keyframes, const std::string& truth) {
  return absoluteTrajectoryError(Trajectory::load(keyframes), Trajectory::load(truth)).alignment;
}

std::string scoreOf(const std::string& map, const std::string& scene,
                    const std::string& trajectory) {
  // Not beside the map: a shared one (sharedMap()) is scored by several processes at once.
  static const std::string scores = processDir("scores");
  static int scored = 0;
  const std::string json = scores + "/" + std::to_string(scored++) + ".json";
  std::string output;
  EXPECT_EQ(run(binary() + " evaluate map " + map + " --scene " + scene + " --trajectory " +
                    trajectory + " --json " + json,
                &output),
            0)
      << output;
  return readFile(json);
}

double trajectoryError(const Trajectory& estimate, const Trajectory& truth) {
  return absoluteTrajectoryError(estimate, truth).translation.rmse;
}

double precisionOf(const std::string& map, const std::string& scene,
                   const std::string& trajectory) {
  return jsonNumber(scoreOf(map, scene, trajectory), "precision");
}

}  // namespace rgbdmap::test
