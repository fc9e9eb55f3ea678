// `rgbdmap synth`: a synthetic TUM-layout sequence of a room with exact geometry, to map and
// score without a camera or a download.
#include <cstdio>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <sstream>
#include <string>

#include "rgbdmap/sim/synthetic_scene.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "rgbdmap/tools/commands.hpp"

namespace rgbdmap {
namespace {

// "6x5x3" -> (6, 5, 3); false unless the room has space for the furniture and a camera path.
bool parseRoomSize(const std::string& text, Eigen::Vector3d& size) {
  double x = 0, y = 0, z = 0;
  char sep1 = 0, sep2 = 0;
  std::istringstream in(text);
  if (!(in >> x >> sep1 >> y >> sep2 >> z) || sep1 != 'x' || sep2 != 'x' || !in.eof()) return false;
  if (!(x >= 3.0 && y >= 3.0 && z >= 2.0 && x <= 100.0 && y <= 100.0 && z <= 20.0)) return false;
  size = Eigen::Vector3d(x, y, z);
  return true;
}

// What `synth` was asked.
struct SynthOptions {
  std::string out, scene, room;
  bool no_noise = false;
  SyntheticSequenceOptions sequence;
};

// Writes the sequence `o` asks for and says where (`noise_seed_given`: --noise-seed was given,
// else the noise takes --seed).
int synth(const SynthOptions& o, bool noise_seed_given) {
#if defined(__SANITIZE_THREAD__)
  // OpenCV's parallel loops run on TBB's workers, which are not instrumented: the sanitizer
  // cannot see them finish and would report every image they wrote. Serial in that build.
  cv::setNumThreads(1);
#endif
  SyntheticSequenceOptions options = o.sequence;
  options.noise = !o.no_noise;
  if (!noise_seed_given) options.noise_seed = options.seed;
  Eigen::Vector3d size(5.0, 4.0, 2.8);
  if (!o.room.empty()) parseRoomSize(o.room, size);
  const SyntheticScene scene =
      o.scene.empty() ? SyntheticScene::defaultRoom(size) : SyntheticScene::load(o.scene);
  if (o.out.find("freiburg") != std::string::npos)
    std::fprintf(stderr,
                 "rgbdmap synth: warning: '%s' contains 'freiburg', so rgbdmap would pick a "
                 "TUM freiburg camera preset for it; this sequence uses the default "
                 "intrinsics (pass --config default when mapping it)\n",
                 o.out.c_str());
  const SyntheticSequenceSummary summary = writeSyntheticSequence(o.out, scene, options);
  std::printf(
      "wrote %d frames to %s in %.1f s (%.1f%% of pixels with depth, %zu visible surface "
      "samples)\nmap it:   rgbdmap --source tum:%s --out map.pcd --rate max\nscore it: "
      "rgbdmap evaluate map map.pcd --scene %s\n",
      summary.frames, o.out.c_str(), summary.seconds, 100.0 * summary.valid_depth_share,
      summary.surface_points, o.out.c_str(), o.out.c_str());
  return 0;
}

}  // namespace

void addSynthCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "synth",
      "write a synthetic RGB-D sequence (TUM layout) of a room with exact geometry: Kinect-like "
      "depth noise, ground truth, scene.yaml and visible_surface.pcd for `rgbdmap evaluate`");
  auto o = std::make_shared<SynthOptions>();
  cmd->add_option("-o,--out", o->out, "folder to write (created if missing)")->required();
  cmd->add_option("-n,--frames", o->sequence.frames, "number of frames")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--seed", o->sequence.seed, "random seed of the path's sway (and of the noise)")
      ->capture_default_str();
  auto* noise_seed = cmd->add_option(
      "--noise-seed", o->sequence.noise_seed,
      "random seed of the sensor noise alone (default: --seed): the same path with fresh noise");
  cmd->add_option("--room", o->room,
                  "size of the built-in room, LENGTHxWIDTHxHEIGHT in metres (default 5x4x2.8; "
                  "the furniture moves with the walls)")
      ->check([](const std::string& text) -> std::string {
        Eigen::Vector3d size;
        return parseRoomSize(text, size) ? "" : "expected e.g. 6x5x3 (x, y >= 3 m, z >= 2 m)";
      });
  cmd->add_option("--path-radius", o->sequence.path_radius,
                  "radius of the camera's circle in metres (default: 16% of the room's length, "
                  "15% of its width)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--path", o->sequence.path,
                  "camera path: orbit (a circle round the room's centre, looking out), walk "
                  "(round the room along its walls, back to the start every lap: loops to "
                  "close) or line (once along a wall, never back)")
      ->capture_default_str()
      ->check(CLI::IsMember({"orbit", "walk", "line"}));
  cmd->add_option("--path-inset", o->sequence.path_inset,
                  "walk, line: metres between the path and the walls (default: 20% of the "
                  "room's width, 0.8 to 1.5 m)")
      ->check(CLI::Range(0.0, 50.0));
  cmd->add_option("--depth-scale-error", o->sequence.depth_scale_error,
                  "sensor error: depth reads this fraction too far (0.01: 1% too far)")
      ->capture_default_str()
      ->check(CLI::Range(-0.19, 0.19));
  cmd->add_option("--focal-error", o->sequence.focal_error,
                  "sensor error: the lens' focal lengths are this fraction above the declared "
                  "intrinsics (a miscalibrated camera)")
      ->capture_default_str()
      ->check(CLI::Range(-0.19, 0.19));
  cmd->add_option("--brightness-drift", o->sequence.brightness_drift,
                  "sensor error: the colour gain swings by +-this fraction every 6 s "
                  "(auto-exposure)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.89));
  cmd->add_flag("--no-noise", o->no_noise,
                "exact depth (only quantised to 1/depth_scale), no dropouts, no colour noise");
  cmd->add_option("--fps", o->sequence.fps, "frame rate (Hz)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--loop-seconds", o->sequence.loop_seconds,
                  "seconds for one circle (orbit) or lap (walk) of the room (smaller: faster "
                  "camera)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--dropout", o->sequence.dropout, "share of depth pixels missing at random")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.99));
  cmd->add_option("--max-incidence", o->sequence.max_incidence_deg,
                  "degrees: surfaces seen more obliquely give no depth")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 90.0));
  cmd->add_option("--scene", o->scene,
                  "scene description (YAML, as the scene.yaml it writes); "
                  "default: the built-in room");
  cmd->add_option("--png-compression", o->sequence.png_compression, "zlib level 0..9")
      ->capture_default_str()
      ->check(CLI::Range(0, 9));
  cmd->callback([o, noise_seed, &selected] {
    selected = [o, noise_seed] { return synth(*o, noise_seed->count() > 0); };
  });
}

}  // namespace rgbdmap
