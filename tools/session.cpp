// `rgbdmap session MAP.session`: reads a saved session through, says what it holds, and refuses
// one that is from another format version, truncated or corrupt (exit 2, naming the file).
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/map_files/pcd_file.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/tools/commands.hpp"

namespace rgbdmap {

void addSessionCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "session", "check a saved session (MAP.session) and say what it holds (docs/sessions.md)");
  auto path = std::make_shared<std::string>();
  auto map = std::make_shared<std::string>();
  auto trajectory = std::make_shared<std::string>();
  cmd->add_option("session", *path, "the session folder, MAP.session beside MAP.pcd")->required();
  cmd->add_option("--map", *map,
                  "also fuse the session's kept keyframes at the graph's poses and write the map "
                  "it holds to this PCD");
  cmd->add_option("--trajectory", *trajectory,
                  "also write the graph's keyframe poses (optimised) to this file, TUM format, in "
                  "time order: a continued session's runs in one frame");
  cmd->callback([path, map, trajectory, &selected] {
    selected = [path, map, trajectory] {
      const Session session = readSession(*path);
      const SessionSummary s = summarise(session, *path);
      std::size_t place_points = 0;
      for (const auto& place : session.graph.places)
        if (place) place_points += place->view.points.size();
      // (A continued session holds two runs, each in its own time.)
      double first = 0, last = 0;
      if (!session.graph.keyframes.empty()) {
        first = last = session.graph.keyframes.front().timestamp;
        for (const auto& k : session.graph.keyframes) {
          first = std::min(first, k.timestamp);
          last = std::max(last, k.timestamp);
        }
      }
      std::printf(
          "%s: rgbdmap session, format version %u, %.1f MB\n"
          "  pose graph: %zu keyframes (%.1f s, stamps %.6f to %.6f), %zu edges (%zu loops)\n"
          "  places: %zu (%zu ORB features with 3-D points, and dense references)\n"
          "  map: %zu kept keyframes (compressed images, fused again at their poses)\n"
          "  camera %dx%d, fx %.2f fy %.2f cx %.2f cy %.2f\n",
          path->c_str(), Session::kFormatVersion, static_cast<double>(s.bytes) / (1024.0 * 1024.0),
          s.keyframes, last - first, first, last, s.edges, s.loop_edges, s.places, place_points,
          s.kept_keyframes, session.camera.width, session.camera.height, session.camera.fx,
          session.camera.fy, session.camera.cx, session.camera.cy);
      if (!trajectory->empty()) {
        graphTrajectory(session).save(*trajectory);
        std::printf("trajectory: %zu keyframe poses written to %s\n",
                    session.graph.keyframes.size(), trajectory->c_str());
      }
      if (!map->empty()) {
        // With the run's own configuration: the same voxels, filters and observation count.
        Config config;
        config.loadYaml(*path + "/config.yaml");
        static_cast<CameraIntrinsics&>(config.camera) = session.camera;
        const auto start = std::chrono::steady_clock::now();
        RunStats stats;
        PoseCorrections corrections;
        Mapper mapper(session.camera, config.filter, config.map, config.refusion, stats,
                      &corrections);
        fuseSession(session, corrections, mapper);
        const std::shared_ptr<const MapCloud> cloud = mapper.snapshot();
        std::string error;
        if (!writePcdAtomically(*cloud, *map, error)) throw InputError(error);
        std::printf(
            "map: %zu points from %zu kept keyframes written to %s in %.1f s\n", cloud->size(),
            session.keyframes.size(), map->c_str(),
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      }
      return 0;
    };
  });
}

}  // namespace rgbdmap
