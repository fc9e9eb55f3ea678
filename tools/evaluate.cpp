// `rgbdmap evaluate`: score a map against the exact geometry of a synthetic sequence, or an
// estimated trajectory against groundtruth (TUM's ATE and RPE).
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/eval/map_evaluation.hpp"
#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/tools/commands.hpp"

namespace rgbdmap {
namespace {

void writeJson(const std::string& path, const std::string& json) {
  if (path.empty()) return;
  std::ofstream out(path);
  out << json;
  out.flush();
  if (!out) throw InputError(path + ": cannot write the JSON results");
}

std::string statisticsJson(const char* prefix, const ErrorStatistics& s, const char* unit) {
  char text[512];
  std::snprintf(text, sizeof(text),
                "  \"%s_rmse_%s\": %.6f,\n  \"%s_mean_%s\": %.6f,\n  \"%s_median_%s\": %.6f,\n"
                "  \"%s_max_%s\": %.6f,\n  \"%s_pairs\": %zu",
                prefix, unit, s.rmse, prefix, unit, s.mean, prefix, unit, s.median, prefix, unit,
                s.max, prefix, s.count);
  return text;
}

int evaluateMapCommand(const std::string& map_path, const std::string& scene, double tau,
                       const std::string& trajectory, const std::string& align,
                       const std::string& json) {
  const SyntheticGroundTruth truth = loadSyntheticGroundTruth(scene);
  pcl::PointCloud<pcl::PointXYZRGB> map = loadMapFile(map_path);
  if (!trajectory.empty()) {
    // A map made from odometry lives in its first camera's frame: moved onto the scene's by its
    // trajectory, so that the score is the map's, not the frame's.
    const Trajectory estimate = Trajectory::load(trajectory);
    const Trajectory groundtruth = Trajectory::load(scene + "/groundtruth.txt");
    const AbsoluteTrajectoryError ate = absoluteTrajectoryError(estimate, groundtruth);
    const Eigen::Isometry3d alignment =
        align == "positions" ? ate.alignment : alignViews(estimate, groundtruth);
    for (auto& p : map.points) p.getVector3fMap() = alignment.cast<float>() * p.getVector3fMap();
    std::printf("aligned     by %s's %s (ATE %.2f mm over %zu poses)\n", trajectory.c_str(),
                align == "positions" ? "positions" : "camera views", 1000.0 * ate.translation.rmse,
                ate.translation.count);
  }
  const MapScore s = evaluateMap(map, truth.scene, truth.visible_surface, tau);
  std::printf("map         %s (%zu points)\n", map_path.c_str(), s.map_points);
  std::printf("reference   %s (%zu visible surface samples)\n", scene.c_str(), s.reference_points);
  std::printf("tau         %.1f mm\n", 1000.0 * tau);
  std::printf("precision   %.4f   (map points within tau of the exact surface)\n", s.precision);
  std::printf("recall      %.4f   (visible surface with a map point within tau)\n", s.recall);
  std::printf("F-score     %.4f\n", s.f_score);
  std::printf("distance    mean %.2f mm   median %.2f mm   p95 %.2f mm\n", 1000.0 * s.mean_distance,
              1000.0 * s.median_distance, 1000.0 * s.p95_distance);
  writeJson(json, s.toJson());
  return 0;
}

int evaluateTrajectoryCommand(const std::string& estimate_path, const std::string& groundtruth_path,
                              double max_difference, double interval, const std::string& json) {
  const Trajectory estimate = Trajectory::load(estimate_path);
  const Trajectory groundtruth = Trajectory::load(groundtruth_path);
  if (estimate.empty()) throw InputError(estimate_path + ": no poses");
  if (groundtruth.empty()) throw InputError(groundtruth_path + ": no poses");
  const AbsoluteTrajectoryError ate =
      absoluteTrajectoryError(estimate, groundtruth, max_difference);
  std::printf("estimate      %s (%zu poses)\n", estimate_path.c_str(), estimate.size());
  std::printf("groundtruth   %s (%zu poses)\n", groundtruth_path.c_str(), groundtruth.size());
  std::printf("ATE (m)       rmse %.4f   mean %.4f   median %.4f   max %.4f   (%zu pairs)\n",
              ate.translation.rmse, ate.translation.mean, ate.translation.median,
              ate.translation.max, ate.translation.count);
  std::string body = "{\n" + statisticsJson("ate", ate.translation, "m");
  try {
    const RelativePoseError rpe = relativePoseError(estimate, groundtruth, interval);
    std::printf("RPE %.2g s (m)   rmse %.4f   mean %.4f   median %.4f   max %.4f   (%zu pairs)\n",
                interval, rpe.translation.rmse, rpe.translation.mean, rpe.translation.median,
                rpe.translation.max, rpe.translation.count);
    std::printf("RPE %.2g s (deg) rmse %.3f   mean %.3f   median %.3f   max %.3f\n", interval,
                rpe.rotation.rmse, rpe.rotation.mean, rpe.rotation.median, rpe.rotation.max);
    body += ",\n  \"rpe_interval_s\": " + std::to_string(interval) + ",\n" +
            statisticsJson("rpe_trans", rpe.translation, "m") + ",\n" +
            statisticsJson("rpe_rot", rpe.rotation, "deg");
  } catch (const InputError& e) {
    std::printf("RPE           not available: %s\n", e.what());
  }
  writeJson(json, body + "\n}\n");
  return 0;
}

}  // namespace

void addEvaluateCommand(CLI::App& app, Command& selected) {
  auto* cmd =
      app.add_subcommand("evaluate",
                         "score a map against a synthetic scene (map), or a trajectory against "
                         "groundtruth with TUM's ATE/RPE (trajectory)");
  cmd->require_subcommand(1);

  struct MapOptions {
    std::string map, scene, json, trajectory, align = "views";
    double tau = 0.01;
  };
  auto m = std::make_shared<MapOptions>();
  auto* map_cmd = cmd->add_subcommand(
      "map",
      "precision, recall, F-score at tau and distances of a map (PCD/PLY) to the exact "
      "surfaces of a sequence written by `rgbdmap synth`");
  map_cmd->add_option("map", m->map, "map file (.pcd or .ply)")->required();
  map_cmd
      ->add_option("--scene", m->scene, "sequence folder with scene.yaml and visible_surface.pcd")
      ->required();
  map_cmd->add_option("--tau", m->tau, "distance threshold (m)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  map_cmd->add_option("--trajectory", m->trajectory,
                      "the map's trajectory (e.g. MAP_trajectory.txt): the map is first moved by "
                      "the alignment of this trajectory to the scene's groundtruth.txt (maps "
                      "made with odometry are in the first camera's frame)");
  map_cmd
      ->add_option("--align", m->align,
                   "with --trajectory: views moves the cameras' views onto the groundtruth ones "
                   "(centres and points ahead of them: fixes the tilt of a trajectory at one "
                   "height); positions moves the centres only, as the ATE does")
      ->capture_default_str()
      ->check(CLI::IsMember({"views", "positions"}));
  map_cmd->add_option("--json", m->json, "also write the results as JSON");
  map_cmd->callback([m, &selected] {
    selected = [m] {
      return evaluateMapCommand(m->map, m->scene, m->tau, m->trajectory, m->align, m->json);
    };
  });

  struct TrajectoryOptions {
    std::string estimate, groundtruth, json;
    double max_difference = 0.02, interval = 1.0;
  };
  auto t = std::make_shared<TrajectoryOptions>();
  auto* trajectory_cmd = cmd->add_subcommand(
      "trajectory", "ATE (after rigid alignment) and RPE of an estimated TUM trajectory");
  trajectory_cmd->add_option("--estimate", t->estimate, "estimated trajectory (TUM format)")
      ->required();
  trajectory_cmd->add_option("--groundtruth", t->groundtruth, "groundtruth (TUM format)")
      ->required();
  trajectory_cmd->add_option("--max-difference", t->max_difference, "association window (s)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  trajectory_cmd->add_option("--interval", t->interval, "RPE interval (s)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  trajectory_cmd->add_option("--json", t->json, "also write the results as JSON");
  trajectory_cmd->callback([t, &selected] {
    selected = [t] {
      return evaluateTrajectoryCommand(t->estimate, t->groundtruth, t->max_difference, t->interval,
                                       t->json);
    };
  });
}

}  // namespace rgbdmap
