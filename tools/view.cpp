// `rgbdmap view MAP.pcd`, and the live viewer of a mapping run.
#include <spdlog/spdlog.h>

#include <filesystem>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_names.hpp"
#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/map_files/ply_file.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/tools/commands.hpp"
#include "rgbdmap/tools/run_viewer.hpp"
#include "rgbdmap/viewer/display_check.hpp"

namespace rgbdmap {
namespace {

// The camera's path: the per-frame trajectory (MAP_trajectory.txt) when there is one, else the
// keyframes (MAP_keyframes.txt); keyframes are marked.
std::vector<TrajectoryPoint> savedTrajectory(const std::string& map_path,
                                             Eigen::Isometry3d& first) {
  Trajectory keyframes, frames;
  const PipelineOutputs beside = outputsBeside(map_path);
  for (auto [path, trajectory] : {std::pair{beside.trajectory_path, &keyframes},
                                  std::pair{beside.frame_trajectory_path, &frames}}) {
    if (!pathExists(path)) continue;
    *trajectory = Trajectory::load(path);  // InputError names the file and line
    spdlog::info("view: {} poses from {}", trajectory->size(), path);
  }
  const Trajectory& path = frames.empty() ? keyframes : frames;
  std::vector<TrajectoryPoint> points;
  std::size_t next_keyframe = 0;  // both files are in time order
  for (const StampedPose& p : path.poses()) {
    while (next_keyframe < keyframes.size() &&
           keyframes[next_keyframe].timestamp < p.timestamp - 1e-6)
      ++next_keyframe;
    const bool keyframe = next_keyframe < keyframes.size() &&
                          keyframes[next_keyframe].timestamp <= p.timestamp + 1e-6;
    points.push_back({p.pose.translation(), keyframe});
  }
  if (!path.empty()) first = path[0].pose;
  return points;
}

}  // namespace

std::unique_ptr<Viewer> openRunViewer(const std::string& mode, RunControl& control,
                                      const std::string& map_path) {
  if (mode == "none") return nullptr;
  std::string why;
  if (!displayAvailable(why)) {
    spdlog::info("viewer: no display ({}): mapping without a viewer", why);
    return nullptr;
  }
  ViewerOptions options;
  options.title = "rgbdmap: " + map_path;
  options.on_snapshot = [&control] { control.snapshot.store(true); };
  options.on_stop = [&control] { control.stop.store(true); };
  return std::make_unique<Viewer>(std::move(options));
}

void addViewCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "view", "open a saved map with its trajectory (MAP_keyframes.txt, MAP_trajectory.txt)");
  auto map = std::make_shared<std::string>();
  cmd->add_option("map", *map, "map file (.pcd or .ply) or mesh (.ply, --mesh)")->required();
  cmd->callback([map, &selected] {
    selected = [map] {
      std::string why;
      if (!displayAvailable(why))
        throw InputError("rgbdmap view: no display to open a window on (" + why +
                         "); `rgbdmap render` draws a map to a PNG without one");
      // A PLY with faces (--mesh) is shown as a mesh; anything else as points.
      std::shared_ptr<TriangleMesh> mesh;
      if (endsWith(*map, ".ply")) {
        try {
          mesh = std::make_shared<TriangleMesh>(readPly(*map));
        } catch (const InputError&) {
          mesh.reset();  // e.g. an ASCII PLY: PCL's reader below says what is wrong
        }
        if (mesh && mesh->empty()) mesh.reset();
      }
      auto cloud = mesh ? nullptr : std::make_shared<MapCloud>(loadMapFile(*map));
      Eigen::Isometry3d first = Eigen::Isometry3d::Identity();
      const std::vector<TrajectoryPoint> trajectory = savedTrajectory(*map, first);
      ViewerOptions options;
      options.title = "rgbdmap: " + *map;
      options.caption = std::filesystem::path(*map).filename().string();
      options.follow = false;
      Viewer viewer(options);
      viewer.mailbox().publishTrajectory(trajectory, first);
      if (mesh)
        viewer.mailbox().publishMesh(mesh);
      else
        viewer.mailbox().publishMap(cloud);
      viewer.waitUntilClosed();
      return 0;
    };
  });
}

}  // namespace rgbdmap
