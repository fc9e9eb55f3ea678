// `rgbdmap calibrate --source SRC`: the colour camera's focal length (or the depth camera's, when
// its intrinsics are not given) and where the depth camera sits in it, for cameras whose depth is
// not registered to colour (raw Kinect streams, 7-Scenes), found from a recording where objects
// stand before others; prints the keys to set.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/base/worker_pool.hpp"
#include "rgbdmap/capture/lens_undistortion.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/runtime/source_factory.hpp"
#include "rgbdmap/tools/commands.hpp"
#include "rgbdmap/tracking/color_depth_calibrator.hpp"

namespace rgbdmap {
namespace {

struct CalibrateOptions {
  std::string source;
  std::string config_file;
  std::vector<std::string> sets;
  std::string out;  // a config file with the calibration, to pass as --config
  int frames = 60;  // captures to use
  int every = 5;    // one capture taken every this many frames
  int threads = 0;
  // Keep camera.depth_z as given, or estimate it; by default kept only when the depth camera's
  // focal length is what is estimated (the two trade against each other, docs/cameras.md).
  bool fix_depth_z = false;
  bool free_depth_z = false;
};

// Every `every`-th capture, up to `frames` of them, as the calibrator takes them: grey colour
// through an ideal pinhole lens, depth as the depth camera measured it.
std::vector<CalibrationFrame> readCaptures(FrameSource& source, const CameraIntrinsics& color,
                                           const CalibrateOptions& o) {
  std::vector<CalibrationFrame> out;
  std::unique_ptr<LensUndistortion> lens;
  if (color.hasDistortion()) lens = std::make_unique<LensUndistortion>(color);
  Frame frame;
  std::uint64_t index = 0;
  int timeouts = 0;
  cv::Mat gray8, pinhole;
  while (static_cast<int>(out.size()) < o.frames) {
    const ReadStatus status = source.read(frame);
    if (status == ReadStatus::kEnd) break;
    if (status == ReadStatus::kTimeout && ++timeouts > 5)
      throw InputError(source.describe() + ": no frames for several seconds");
    if (status != ReadStatus::kFrame) continue;
    if (index++ % static_cast<std::uint64_t>(o.every) != 0) continue;
    if (frame.color.size() != cv::Size(color.width, color.height))
      throw InputError(frame.origin + ": the colour image is " + std::to_string(frame.color.cols) +
                       "x" + std::to_string(frame.color.rows) + ", the camera section says " +
                       std::to_string(color.width) + "x" + std::to_string(color.height));
    CalibrationFrame capture;
    cv::cvtColor(frame.color, gray8, cv::COLOR_BGR2GRAY);
    if (lens) {
      lens->resampleImage(gray8, pinhole);
      pinhole.convertTo(capture.gray, CV_32F);
    } else {
      gray8.convertTo(capture.gray, CV_32F);
    }
    capture.depth = frame.depth.clone();
    out.push_back(std::move(capture));
  }
  return out;
}

int calibrate(const CalibrateOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  Config config;
  config.loadPreset(o.config_file.empty() ? presetForSource(o.source) : o.config_file);
  config.set("replay.rate", "0", "calibrate");  // recordings: every frame
  config.setAll(o.sets, "--set");
  std::unique_ptr<FrameSource> source = openSource(o.source, config);
  const CameraOptions& camera = config.camera;
  // Registered depth (no camera.depth_* keys: a check of a registered camera) shares the colour
  // lens; a depth camera of its own is an ideal pinhole, as DepthRegistration takes it.
  const CameraIntrinsics depth = camera.depthCamera();
  // Without the depth camera's own intrinsics its focal length is what is unknown (taken from
  // the colour camera's to start with); with them (a dataset's, a preset's), the colour's.
  const bool depth_focal_unknown = !(camera.depth_fx > 0);

  const std::vector<CalibrationFrame> captures = readCaptures(*source, camera, o);
  if (captures.size() < 2)
    throw InputError(source->describe() + ": " + std::to_string(captures.size()) +
                     " captures taken; calibrating needs several (a longer recording, or a "
                     "smaller --every)");

  ColorDepthCalibration guess;
  guess.fx = camera.fx;
  guess.fy = camera.fy;
  guess.color_from_depth = camera.colorFromDepth();

  WorkerPool pool(WorkerPool::resolve(o.threads));
  ColorDepthCalibrator::Config calibrator_config;
  calibrator_config.min_depth = config.filter.min_depth;
  calibrator_config.max_depth = config.filter.max_depth;
  const bool fix_depth_z = o.fix_depth_z || (depth_focal_unknown && !o.free_depth_z);
  calibrator_config.estimate_depth_z = !fix_depth_z;
  calibrator_config.estimate_depth_focal = depth_focal_unknown;
  const ColorDepthCalibrator calibrator(calibrator_config, camera, depth);
  CalibrationReport report;
  try {
    report = calibrator.estimate(captures, guess, pool);
  } catch (const std::runtime_error& e) {
    throw InputError(source->describe() + ": cannot calibrate: " + e.what());
  }

  const ColorDepthCalibration& c = report.calibration;
  const Eigen::AngleAxisd rotation(c.color_from_depth.linear());
  const Eigen::Vector3d rv = rotation.angle() * rotation.axis();
  const Eigen::Vector3d t = c.color_from_depth.translation();
  std::printf(
      "%s: %zu captures; depth outlines %.2f px from the colour edges (RMS, %zu matched) with "
      "the keys given, %.2f px (%zu) calibrated (%.1f s)\n",
      source->describe().c_str(), captures.size(), report.rms_before, report.edges_before,
      report.rms_after, report.edges_after, secondsSince(start));
  const double depth_fx = depth.fx * c.depth_focal_scale, depth_fy = depth.fy * c.depth_focal_scale;
  if (depth_focal_unknown)
    std::printf(
        "depth camera: fx %.2f, fy %.2f (no camera.depth_fx/fy given: started from the colour "
        "camera's %.2f, %.2f, which are kept; principal point kept)\n",
        depth_fx, depth_fy, camera.fx, camera.fy);
  else
    std::printf("colour camera: fx %.2f, fy %.2f (given %.2f, %.2f; principal point kept)\n", c.fx,
                c.fy, camera.fx, camera.fy);
  std::printf("uncertainty: position %.1f mm, rotation %.3f deg, focal length %.2f%%\n",
              report.translation_sd * 1000, report.rotation_sd * 180 / M_PI, report.focal_sd * 100);
  std::printf(
      "depth camera in the colour camera: %.4f %.4f %.4f m, rotation %.3f %.3f %.3f deg%s\n", t.x(),
      t.y(), t.z(), rv.x() * 180 / M_PI, rv.y() * 180 / M_PI, rv.z() * 180 / M_PI,
      fix_depth_z ? " (along the view kept at camera.depth_z)" : "");
  // Measured on rendered rooms: where these (optimistic) spreads were above 1 mm or 0.1%, the
  // estimate was off by centimetres and percent; below, by 2 mm and 0.2% at most.
  if (report.translation_sd > 0.001 || report.focal_sd > 0.001)
    std::fprintf(stderr,
                 "warning: %s determines the calibration poorly: film objects standing before "
                 "others (chairs, shelves, door frames) from nearer and from more sides, or take "
                 "more captures (--frames, --every)\n",
                 source->describe().c_str());
  // Kinect-class cameras hold their lenses centimetres apart and parallel to a degree: more
  // says the depth camera's intrinsics are not its own (or the depth is registered already).
  if (t.norm() > 0.05 || rotation.angle() > 2.0 * M_PI / 180)
    std::fprintf(stderr,
                 "warning: a depth camera %.1f cm and %.1f deg from the colour one is not a "
                 "Kinect-class camera's: check its intrinsics (camera.depth_fx/fy/cx/cy: %g, %g, "
                 "%g, %g), or whether %s's depth is registered to colour already\n",
                 t.norm() * 100, rotation.angle() * 180 / M_PI, depth.fx, depth.fy, depth.cx,
                 depth.cy, source->describe().c_str());
  if (!fix_depth_z && std::abs(t.z() - camera.depth_z) > 0.01)
    std::fprintf(stderr,
                 "warning: the depth camera came out %.1f cm along the view from camera.depth_z: "
                 "Kinect-class cameras hold both lenses on one board, and on real recordings "
                 "that is the focal length traded against depth; try --fix-depth-z\n",
                 (t.z() - camera.depth_z) * 100);

  // The keys, the depth camera's intrinsics included: once camera.fx changes, a depth_fx of 0
  // (the colour camera's) would follow it.
  const std::vector<std::pair<std::string, double>> keys = {
      {"camera.fx", c.fx},           {"camera.fy", c.fy},           {"camera.depth_fx", depth_fx},
      {"camera.depth_fy", depth_fy}, {"camera.depth_cx", depth.cx}, {"camera.depth_cy", depth.cy},
      {"camera.depth_x", t.x()},     {"camera.depth_y", t.y()},     {"camera.depth_z", t.z()},
      {"camera.depth_rx", rv.x()},   {"camera.depth_ry", rv.y()},   {"camera.depth_rz", rv.z()}};
  std::string sets;
  for (const auto& [key, value] : keys) {
    char text[64];
    std::snprintf(text, sizeof text, "%.6g", value);
    sets += " --set " + key + "=" + text;
    config.set(key, text, "calibrate");
  }
  std::printf("map with:%s\n", sets.c_str());
  if (!o.out.empty()) {
    std::ofstream file(o.out);
    file << "# rgbdmap calibrate --source " << o.source << "\n" << config.toYaml();
    file.close();
    if (!file) throw InputError(o.out + ": cannot write");
    std::printf("or: --config %s (every key, the camera calibrated)\n", o.out.c_str());
  }
  return 0;
}

}  // namespace

void addCalibrateCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "calibrate",
      "find the depth camera's pose in the colour camera (depth not registered to colour) and "
      "the colour camera's focal length, or the depth camera's when camera.depth_fx/fy are not "
      "given, from a recording; prints the camera keys to map it with");
  auto o = std::make_shared<CalibrateOptions>();
  cmd->add_option("-s,--source", o->source, "tum:DIR | openni2 | openni2:FILE.oni | ...")
      ->required();
  cmd->add_option("-c,--config", o->config_file,
                  "YAML config: a preset name or a file (the guess: camera.fx/fy, the depth "
                  "camera's camera.depth_* keys)");
  cmd->add_option("--set", o->sets, "override a config key (repeatable)");
  cmd->add_option("-o,--out", o->out, "also write a config file with the calibration");
  cmd->add_option("--frames", o->frames, "captures to use")
      ->capture_default_str()
      ->check(CLI::Range(2, 500));  // each keeps 2.4 MB (grey and depth as floats)
  cmd->add_option("--every", o->every, "take one capture every this many frames")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  auto* fix = cmd->add_flag("--fix-depth-z", o->fix_depth_z,
                            "keep the depth camera's offset along the view at camera.depth_z "
                            "(cameras on one board: see docs/cameras.md); the default when "
                            "camera.depth_fx/fy are not given");
  cmd->add_flag("--free-depth-z", o->free_depth_z,
                "estimate the depth camera's offset along the view (the default when "
                "camera.depth_fx/fy are given)")
      ->excludes(fix);
  cmd->add_option("--threads", o->threads, "threads (0: every core)")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  cmd->callback([o, &selected] { selected = [o] { return calibrate(*o); }; });
}

}  // namespace rgbdmap
