// `rgbdmap synth`: a synthetic TUM-layout sequence of a room with exact geometry, to map and
// score without a camera or a download.
#include <cstdio>
#include <memory>
#include <string>

#include "rgbdmap/sim/synthetic_scene.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "rgbdmap/tools/commands.hpp"

namespace rgbdmap {

void addSynthCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "synth",
      "write a synthetic RGB-D sequence (TUM layout) of a room with exact geometry: Kinect-like "
      "depth noise, ground truth, scene.yaml and visible_surface.pcd for `rgbdmap evaluate`");
  struct Options {
    std::string out, scene;
    bool no_noise = false;
    SyntheticSequenceOptions sequence;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("-o,--out", o->out, "folder to write (created if missing)")->required();
  cmd->add_option("-n,--frames", o->sequence.frames, "number of frames")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--seed", o->sequence.seed, "random seed (noise, path sway)")
      ->capture_default_str();
  cmd->add_flag("--no-noise", o->no_noise,
                "exact depth (only quantised to 1/depth_scale), no dropouts, no colour noise");
  cmd->add_option("--fps", o->sequence.fps, "frame rate (Hz)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--loop-seconds", o->sequence.loop_seconds,
                  "seconds for one circle of the room (smaller: faster camera)")
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
  cmd->callback([o, &selected] {
    selected = [o] {
      SyntheticSequenceOptions options = o->sequence;
      options.noise = !o->no_noise;
      const SyntheticScene scene =
          o->scene.empty() ? SyntheticScene::defaultRoom() : SyntheticScene::load(o->scene);
      if (o->out.find("freiburg") != std::string::npos)
        std::fprintf(stderr,
                     "rgbdmap synth: warning: '%s' contains 'freiburg', so rgbdmap would pick a "
                     "TUM freiburg camera preset for it; this sequence uses the default "
                     "intrinsics (pass --config default when mapping it)\n",
                     o->out.c_str());
      const SyntheticSequenceSummary summary = writeSyntheticSequence(o->out, scene, options);
      std::printf(
          "wrote %d frames to %s in %.1f s (%.1f%% of pixels with depth, %zu visible surface "
          "samples)\nmap it:   rgbdmap --source tum:%s --out map.pcd --rate max\nscore it: "
          "rgbdmap evaluate map map.pcd --scene %s\n",
          summary.frames, o->out.c_str(), summary.seconds, 100.0 * summary.valid_depth_share,
          summary.surface_points, o->out.c_str(), o->out.c_str());
      return 0;
    };
  });
}

}  // namespace rgbdmap
