// `rgbdmap synth`: a synthetic TUM-layout sequence of a room with exact geometry, to map and
// score without a camera or a download.
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <sstream>
#include <string>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/sim/building.hpp"
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

// "30x20" -> (30, 20); false unless both are numbers.
bool parseFloorSize(const std::string& text, double& length, double& width) {
  char sep = 0;
  std::istringstream in(text);
  return static_cast<bool>(in >> length >> sep >> width) && sep == 'x' && in.eof();
}

// What `synth` was asked.
struct SynthOptions {
  std::string out, scene, room, building, write_scene;
  std::string depth_camera;  // "X,Y,Z,RX,RY,RZ": m and degrees
  double height = 2.8;
  bool no_noise = false;
  SyntheticSequenceOptions sequence;
};

// The scene `o` asks for: a generated floor, a YAML scene or the built-in room (a floor's
// reference surface is sampled coarser unless --surface-voxel was given).
SyntheticScene sceneFor(const SynthOptions& o, bool surface_voxel_given,
                        SyntheticSequenceOptions& options) {
  if (!o.building.empty()) {
    BuildingOptions building;
    parseFloorSize(o.building, building.length, building.width);
    building.height = o.height;
    building.seed = options.seed;
    if (!surface_voxel_given) options.surface_voxel = 0.02;
    return generateBuilding(building);
  }
  Eigen::Vector3d size(5.0, 4.0, 2.8);
  if (!o.room.empty()) parseRoomSize(o.room, size);
  return o.scene.empty() ? SyntheticScene::defaultRoom(size) : SyntheticScene::load(o.scene);
}

// Writes what `o` asks for and says where (the *_given flags: whether the option was on the
// command line).
int synth(const SynthOptions& o, bool noise_seed_given, bool frames_given,
          bool surface_voxel_given) {
#if defined(__SANITIZE_THREAD__)
  // OpenCV's parallel loops run on TBB's workers, which are not instrumented: the sanitizer
  // cannot see them finish and would report every image they wrote. Serial in that build.
  cv::setNumThreads(1);
#endif
  SyntheticSequenceOptions options = o.sequence;
  options.noise = !o.no_noise;
  if (!noise_seed_given) options.noise_seed = options.seed;
  if (o.out.empty() && o.write_scene.empty())
    throw InputError("synth: --out FOLDER is required (or --write-scene FILE alone)");
  if (!o.building.empty() && (!o.scene.empty() || !o.room.empty()))
    throw InputError("synth: --building makes its own scene; leave out --scene and --room");
  if (options.path == "tour" && !frames_given) options.frames = 0;  // one whole tour
  if (!o.depth_camera.empty()) {
    double v[6];
    char end = 0;
    if (std::sscanf(o.depth_camera.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3],
                    &v[4], &v[5], &end) != 6 ||
        Eigen::Vector3d(v[0], v[1], v[2]).norm() > 0.2 ||
        Eigen::Vector3d(v[3], v[4], v[5]).norm() > 10.0)
      throw InputError("synth: --depth-camera '" + o.depth_camera +
                       "': expected X,Y,Z,RX,RY,RZ (m within 0.2, rotation vector in degrees "
                       "within 10)");
    options.depth_camera_position = {v[0], v[1], v[2]};
    options.depth_camera_rotation = Eigen::Vector3d(v[3], v[4], v[5]) * M_PI / 180.0;
  }
  if (options.depth_focal != 0 && !(options.depth_focal >= 100 && options.depth_focal <= 3000))
    throw InputError("synth: --depth-focal " + fmt::format("{:g}", options.depth_focal) +
                     ": expected a focal length of 100-3000 px (or 0: the colour camera's)");
  const SyntheticScene scene = sceneFor(o, surface_voxel_given, options);
  if (!o.write_scene.empty()) {
    try {
      scene.save(o.write_scene);
    } catch (const std::runtime_error& e) {
      throw InputError(e.what());
    }
    std::printf("wrote the scene to %s (%zu primitives, %zu walls%s)\n", o.write_scene.c_str(),
                scene.primitives().size(), scene.walls().size(),
                scene.floorPlan() ? ", a floor plan" : "");
    if (o.out.empty()) return 0;
  }
  if (o.out.find("freiburg") != std::string::npos)
    std::fprintf(stderr,
                 "rgbdmap synth: warning: '%s' contains 'freiburg', so rgbdmap would pick a "
                 "TUM freiburg camera preset for it; this sequence uses the default "
                 "intrinsics (pass --config default when mapping it)\n",
                 o.out.c_str());
  const SyntheticSequenceSummary summary = writeSyntheticSequence(o.out, scene, options);
  if (summary.path_seconds > 0.0)
    std::printf("tour: %.0f m in %.1f s (%d frames at %.0f fps, one tour: %.0f frames)\n",
                summary.path_length, summary.path_seconds, summary.frames, options.fps,
                std::floor(summary.path_seconds * options.fps) + 1);
  std::printf(
      "wrote %d frames to %s in %.1f s (%.1f%% of pixels with depth, %zu visible surface "
      "samples)\nmap it:   rgbdmap --source tum:%s --out map.pcd --rate max\nscore it: "
      "rgbdmap evaluate map map.pcd --scene %s\n",
      summary.frames, o.out.c_str(), summary.seconds, 100.0 * summary.valid_depth_share,
      summary.surface_points, o.out.c_str(), o.out.c_str());
  if (options.depthUnregistered()) {
    const Eigen::Vector3d& t = options.depth_camera_position;
    const Eigen::Vector3d& r = options.depth_camera_rotation;
    const double f = options.depth_focal > 0 ? options.depth_focal : options.camera.fx;
    std::printf(
        "depth is not registered to colour; its camera: --set camera.depth_fx=%g --set "
        "camera.depth_fy=%g --set camera.depth_x=%g --set camera.depth_y=%g --set "
        "camera.depth_z=%g --set camera.depth_rx=%g --set camera.depth_ry=%g --set "
        "camera.depth_rz=%g\n",
        f, f, t.x(), t.y(), t.z(), r.x(), r.y(), r.z());
  }
  return 0;
}

// The options of a generated floor and its tour; returns --surface-voxel's (a floor samples its
// reference coarser unless it is given).
CLI::Option* addBuildingOptions(CLI::App& cmd, SynthOptions& o) {
  cmd.add_option("--building", o.building,
                 "an office floor of LENGTHxWIDTH metres instead of a room (e.g. 30x20): rooms "
                 "off a corridor, doors, furniture; --seed changes the plan (see "
                 "docs/synthetic.md)")
      ->check([](const std::string& text) -> std::string {
        double length = 0, width = 0;
        if (!parseFloorSize(text, length, width)) return "expected e.g. 30x20";
        BuildingOptions b;
        b.length = length;
        b.width = width;
        return buildingProblem(b);
      });
  cmd.add_option("--height", o.height, "the building's floor-to-ceiling height (m)")
      ->capture_default_str()
      ->check(CLI::Range(2.4, 5.0));
  cmd.add_option("--write-scene", o.write_scene,
                 "also write the scene description (YAML) to this file, to edit and pass back "
                 "with --scene; without --out nothing else is written");
  auto* surface_voxel =
      cmd.add_option("--surface-voxel", o.sequence.surface_voxel,
                     "m between samples of visible_surface.pcd, the reference for recall "
                     "(default 0.005; 0.02 for a building, to keep a floor's samples in memory)")
          ->check(CLI::Range(0.001, 0.5));
  cmd.add_option("--tour-speed", o.sequence.tour_speed, "the tour's top walking speed (m/s)")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 3.0));
  cmd.add_option("--tour-turn-rate", o.sequence.tour_turn_rate, "the tour's top turn rate (rad/s)")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 3.0));
  return surface_voxel;
}

}  // namespace

void addSynthCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "synth",
      "write a synthetic RGB-D sequence (TUM layout) of a room with exact geometry: Kinect-like "
      "depth noise, ground truth, scene.yaml and visible_surface.pcd for `rgbdmap evaluate`");
  auto o = std::make_shared<SynthOptions>();
  cmd->add_option("-o,--out", o->out,
                  "folder to write (created if missing); required unless --write-scene alone");
  auto* frames = cmd->add_option("-n,--frames", o->sequence.frames,
                                 "number of frames (a tour: default one whole tour)")
                     ->capture_default_str()
                     ->check(CLI::Range(1, 1000000));
  auto* surface_voxel = addBuildingOptions(*cmd, *o);
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
                  "close), line (once along a wall, never back) or tour (a building's: along the "
                  "corridor into every room and back to the start)")
      ->capture_default_str()
      ->check(CLI::IsMember({"orbit", "walk", "line", "tour"}));
  cmd->add_option("--path-inset", o->sequence.path_inset,
                  "walk, line: metres between the path and the walls (default: 20% of the "
                  "room's width, 0.8 to 1.5 m)")
      ->check(CLI::Range(0.0, 50.0));
  cmd->add_option("--depth-scale-error", o->sequence.depth_scale_error,
                  "sensor error: depth reads this fraction too far (0.01: 1% too far)")
      ->capture_default_str()
      ->check(CLI::Range(-0.19, 0.19));
  cmd->add_option("--depth-camera", o->depth_camera,
                  "depth from a camera of its own, not registered to colour: its position (m) "
                  "and rotation vector (degrees) in the colour camera's frame, X,Y,Z,RX,RY,RZ "
                  "(e.g. 0.025,0,0,0,0.5,0; map it with the camera.depth_* keys synthetic.yaml "
                  "gives)");
  cmd->add_option("--depth-focal", o->sequence.depth_focal,
                  "depth from a camera of its own with this focal length (px; 0: the colour "
                  "camera's declared one), e.g. a Kinect's 580; with --focal-error, only the "
                  "colour lens errs");
  cmd->add_option("--focal-error", o->sequence.focal_error,
                  "sensor error: the lens' focal lengths are this fraction above the declared "
                  "intrinsics (a miscalibrated camera)")
      ->capture_default_str()
      ->check(CLI::Range(-0.19, 0.19));
  cmd->add_option("--readout", o->sequence.readout,
                  "sensor: a rolling shutter that reads the rows over this many seconds, top to "
                  "bottom (a Kinect's colour camera: about 0.013); map it with --set "
                  "camera.readout=S")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.1));
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
  cmd->callback([o, noise_seed, frames, surface_voxel, &selected] {
    selected = [o, noise_seed, frames, surface_voxel] {
      return synth(*o, noise_seed->count() > 0, frames->count() > 0, surface_voxel->count() > 0);
    };
  });
}

}  // namespace rgbdmap
