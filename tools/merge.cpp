// `rgbdmap merge A.session B.session ... --out MERGED.pcd`: several runs' sessions joined in the
// first one's frame (SessionMerger), written as one map, one session and each session's transform.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <fstream>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/map_files/pcd_file.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/sessions/session_merge.hpp"
#include "rgbdmap/slam/motion.hpp"
#include "rgbdmap/tools/commands.hpp"

namespace rgbdmap {
namespace {

// "tx ty tz qx qy qz qw", TUM's order.
std::string tumPose(const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.linear());
  const Eigen::Vector3d t = pose.translation();
  char text[160];
  std::snprintf(text, sizeof text, "%.6f %.6f %.6f %.9f %.9f %.9f %.9f", t.x(), t.y(), t.z(), q.x(),
                q.y(), q.z(), q.w());
  return text;
}

int merge(const std::vector<std::string>& paths, const std::string& out) {
  if (paths.size() < 2)
    throw InputError("merge: give two sessions or more (A.session B.session ...)");
  checkOutputFolder(out, "--out");
  const auto start = std::chrono::steady_clock::now();
  std::vector<Session> sessions;
  for (const std::string& path : paths) {
    sessions.push_back(readSession(path));
    const CameraIntrinsics& first = sessions.front().camera;
    const CameraIntrinsics& camera = sessions.back().camera;
    if (camera.width != first.width || camera.height != first.height)
      throw InputError(path + ": camera " + std::to_string(camera.width) + "x" +
                       std::to_string(camera.height) + ", the first session's is " +
                       std::to_string(first.width) + "x" + std::to_string(first.height) +
                       " (sessions of one image size merge)");
    spdlog::info("{}: {} keyframes, {} kept", path, sessions.back().graph.keyframes.size(),
                 sessions.back().keyframes.size());
  }
  // The first session's settings: its voxels, filters and loop closure's checks.
  Config config;
  config.loadYaml(paths.front() + "/config.yaml");
  static_cast<CameraIntrinsics&>(config.camera) = sessions.front().camera;

  std::vector<SessionMerger::Placement> placements;
  const Session merged = SessionMerger(config).merge(sessions, placements);
  std::size_t placed = 0;
  std::ofstream transforms(stem(out) + "_transforms.txt");
  transforms << "# rgbdmap merge: each session's frame in the merged map's (the first session's),"
                " TUM order: session tx ty tz qx qy qz qw\n";
  for (std::size_t i = 0; i < sessions.size(); ++i) {
    const SessionMerger::Placement& p = placements[i];
    if (!p.placed) {
      spdlog::warn("{}: shares no place with the other sessions: left out", paths[i]);
      transforms << "# " << paths[i] << ": not placed (no place shared with the others)\n";
      continue;
    }
    ++placed;
    transforms << paths[i] << " " << tumPose(p.transform) << "\n";
    if (i == 0) continue;
    spdlog::info(
        "{}: placed by {} agreeing places (most of them {}'s), tied by {} places in all: its "
        "frame {:.3f} m and {:.1f} degrees from the first session's",
        paths[i], p.placing, paths[static_cast<std::size_t>(p.linked_to)], p.links,
        p.transform.translation().norm(), rotationAngle(p.transform) * kDegreesPerRadian);
  }
  if (!transforms) throw InputError(stem(out) + "_transforms.txt: cannot write");

  // The map: every placed session's kept keyframes fused at the merged graph's poses.
  RunStats stats;
  PoseCorrections corrections;
  Mapper mapper(merged.camera, config.filter, config.map, config.refusion, stats, &corrections);
  fuseSession(merged, corrections, mapper);
  const std::shared_ptr<const MapCloud> cloud = mapper.snapshot();
  std::string error;
  if (!writePcdAtomically(*cloud, out, error)) throw InputError(error);
  std::uint64_t bytes = 0;
  if (!writeSession(merged, sessionPathOf(out), error, &bytes)) throw InputError(error);
  // One trajectory for the merged map: the graph's keyframes, and every frame the runs tracked
  // (sessions that kept them), at the merged graph's poses.
  graphTrajectory(merged).save(stem(out) + "_keyframes.txt");
  const bool frames = !merged.frames.empty();
  if (frames) resolvedTrajectory(merged, merged.frames).save(stem(out) + "_trajectory.txt");
  spdlog::info(
      "merged {} of {} sessions: {} points written to {}, the session ({:.1f} MB) to {}, the "
      "transforms to {}, the keyframes' poses to {}{} ({:.1f} s)",
      placed, sessions.size(), cloud->size(), out, static_cast<double>(bytes) / (1024.0 * 1024.0),
      sessionPathOf(out), stem(out) + "_transforms.txt", stem(out) + "_keyframes.txt",
      frames ? ", every frame's to " + stem(out) + "_trajectory.txt" : "", secondsSince(start));
  // Nothing joined: the sessions share no place at all.
  return placed > 1 ? 0 : 1;
}

}  // namespace

void addMergeCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "merge",
      "join saved sessions (MAP.session) in the first one's frame: one map, one session, each "
      "session's transform (docs/sessions.md)");
  auto paths = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>("merged.pcd");
  cmd->add_option("sessions", *paths, "the session folders, the first one's frame is kept")
      ->required();
  cmd->add_option("-o,--out", *out,
                  "the merged map (PCD); MERGED.session and MERGED_transforms.txt beside it")
      ->capture_default_str();
  cmd->callback(
      [paths, out, &selected] { selected = [paths, out] { return merge(*paths, *out); }; });
}

}  // namespace rgbdmap
