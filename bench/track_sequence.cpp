// Tracks every frame of a TUM folder with one or more trackers, in the same run, and reports
// for each (OpenCV's frame to frame): ATE RMSE and RPE (TUM's definitions, src/eval) over every
// frame (a lost frame counts with the pose the tracker predicted), frames lost and relocalised, and
// milliseconds per frame spent in tracking alone (PNG decoding excluded), median and p95. The first
// method is the baseline of the ratio columns. Writes each per-frame trajectory as TUM text when
// asked.
//
//   track_sequence --sequence DIR [--methods dense,opencv_rgbd,opencv_rgbd_icp]
//                  [--trajectory-prefix PATH] [--set key=value]... [--json FILE]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"
#include "rgbdmap/tracking/rgbd_odometry.hpp"

namespace {

struct Outcome {
  std::string method;
  rgbdmap::Trajectory trajectory;
  std::vector<double> ms;
  int lost = 0, relocalised = 0;
  double ate = 0, rpe_t = 0, rpe_r = 0, median_ms = 0, p95_ms = 0;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

Outcome track(rgbdmap::TumSequence& sequence, rgbdmap::Config config, const std::string& method) {
  config.pose.source = "odometry";
  config.tracking.method = method;
  std::unique_ptr<rgbdmap::PoseProvider> tracker;
  if (method == "dense") {
    tracker = rgbdmap::makePoseProvider(config.pose, config.tracking, config.camera,
                                        config.filter.min_depth, config.filter.max_depth);
  } else {
    // OpenCV's odometries frame to frame, as the peers were measured: every frame becomes the
    // reference of the next.
    rgbdmap::RgbdOdometryPoses::Options options;
    options.min_depth = config.filter.min_depth;
    options.max_depth = config.filter.max_depth;
    options.new_reference_translation = 0;
    options.new_reference_rotation = 0;
    options.icp = method == "opencv_rgbd_icp";
    tracker = std::make_unique<rgbdmap::RgbdOdometryPoses>(config.camera, options);
  }
  Outcome out;
  out.method = method;
  rgbdmap::Frame frame;
  std::string error;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    if (!sequence.load(i, frame, error)) throw rgbdmap::InputError(error);
    frame.index = i;
    frame.has_pose = false;
    const auto start = std::chrono::steady_clock::now();
    tracker->estimate(frame);
    const auto stop = std::chrono::steady_clock::now();
    out.ms.push_back(std::chrono::duration<double, std::milli>(stop - start).count());
    const rgbdmap::TrackingState state = tracker->state();
    out.lost += state == rgbdmap::TrackingState::kLost;
    out.relocalised += state == rgbdmap::TrackingState::kRelocalised;
    // Every frame, lost or not: a lost frame's pose is the tracker's prediction.
    out.trajectory.push_back({frame.timestamp, frame.pose});
  }
  // The first frame sets up the tracker (no alignment): not a tracking cost.
  std::vector<double> tracked(out.ms.begin() + (out.ms.size() > 1 ? 1 : 0), out.ms.end());
  out.median_ms = percentile(tracked, 0.5);
  out.p95_ms = percentile(tracked, 0.95);
  if (sequence.hasGroundtruth()) {
    out.ate =
        rgbdmap::absoluteTrajectoryError(out.trajectory, sequence.groundtruth()).translation.rmse;
    const rgbdmap::RelativePoseError rpe =
        rgbdmap::relativePoseError(out.trajectory, sequence.groundtruth());
    out.rpe_t = rpe.translation.rmse;
    out.rpe_r = rpe.rotation.rmse;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Track a TUM sequence with rgbdmap's and OpenCV's odometry; ATE, RPE, ms/frame"};
  std::string folder, methods = "dense,opencv_rgbd", prefix, json;
  std::vector<std::string> sets;
  app.add_option("--sequence", folder, "TUM sequence folder")->required();
  app.add_option("--methods", methods,
                 "comma-separated tracking.method values; the first is the ratio baseline");
  app.add_option("--trajectory-prefix", prefix,
                 "write PREFIX<method>.txt, every frame's pose in TUM format");
  app.add_option("--set", sets, "config key=value, as rgbdmap's --set");
  app.add_option("--json", json, "write the results as JSON here");
  CLI11_PARSE(app, argc, argv);
  try {
    rgbdmap::Config config;
    const std::string preset = rgbdmap::TumSequence::presetForFolder(folder);
    config.loadPreset(preset.empty() ? "default" : preset);
    for (const std::string& s : sets) {
      const auto eq = s.find('=');
      if (eq == std::string::npos) throw rgbdmap::InputError("--set " + s + ": expected key=value");
      config.set(s.substr(0, eq), s.substr(eq + 1), "--set");
    }
    rgbdmap::TumSequence::Options options;
    options.depth_scale = config.camera.depth_scale;
    rgbdmap::TumSequence sequence(folder, options);

    std::vector<Outcome> outcomes;
    std::stringstream list(methods);
    for (std::string method; std::getline(list, method, ',');) {
      outcomes.push_back(track(sequence, config, method));
      if (!prefix.empty()) outcomes.back().trajectory.save(prefix + method + ".txt");
    }
    std::printf("%s: %zu frames\n", folder.c_str(), sequence.size());
    std::printf("%-16s %9s %10s %10s %6s %6s %9s %8s %10s %10s\n", "method", "ATE(cm)", "RPE(cm/s)",
                "RPE(deg/s)", "lost", "reloc", "median ms", "p95 ms", "ATE ratio", "time ratio");
    std::ostringstream js;
    js << "{\"sequence\": \"" << folder << "\", \"frames\": " << sequence.size()
       << ", \"methods\": [";
    for (std::size_t i = 0; i < outcomes.size(); ++i) {
      const Outcome& o = outcomes[i];
      const Outcome& base = outcomes.front();
      const double ate_ratio = base.ate > 0 ? o.ate / base.ate : 0;
      const double time_ratio = base.median_ms > 0 ? o.median_ms / base.median_ms : 0;
      std::printf("%-16s %9.2f %10.2f %10.2f %6d %6d %9.2f %8.2f %10.2f %10.2f\n", o.method.c_str(),
                  o.ate * 100, o.rpe_t * 100, o.rpe_r, o.lost, o.relocalised, o.median_ms, o.p95_ms,
                  ate_ratio, time_ratio);
      js << (i ? ", " : "") << "{\"method\": \"" << o.method << "\", \"ate_rmse\": " << o.ate
         << ", \"rpe_translation_rmse\": " << o.rpe_t << ", \"rpe_rotation_rmse\": " << o.rpe_r
         << ", \"lost\": " << o.lost << ", \"relocalised\": " << o.relocalised
         << ", \"median_ms\": " << o.median_ms << ", \"p95_ms\": " << o.p95_ms << "}";
    }
    js << "]}\n";
    if (!json.empty()) std::ofstream(json) << js.str();
  } catch (const std::exception& e) {
    std::cerr << "track_sequence: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
