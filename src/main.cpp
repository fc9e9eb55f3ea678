// rgbdmap: map a room with an RGB-D camera (or a TUM sequence replayed as one)
// into a coloured point cloud, checkpointed while it runs.
#include <spdlog/cfg/env.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <memory>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/runtime/exit_code.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/runtime/pipeline.hpp"
#include "rgbdmap/runtime/pose_source.hpp"
#include "rgbdmap/runtime/run_mode.hpp"
#include "rgbdmap/runtime/run_signals.hpp"
#include "rgbdmap/runtime/source_factory.hpp"
#include "rgbdmap/tools/commands.hpp"
#include "rgbdmap/tools/map_renderer.hpp"
#include "rgbdmap/tools/run_viewer.hpp"

namespace {

// What the command line asks of a mapping run (config keys come through --config and --set).
struct CommandLine {
  std::string config_file;
  std::string source = "";
  std::string out = "map.pcd";
  std::string rate;
  std::vector<std::string> sets;
  std::string stats_file;
  std::string mesh;
  std::string grid;
  std::string octomap;
  std::string localise;       // a saved session to localise in
  std::string continue_from;  // a saved session to continue
  std::string viewer = "auto";
  bool no_render = false;
  bool quiet = false;
  bool list_keys = false;
  bool markdown = false;
};

// A stop requested before mapping began: nothing was mapped and nothing is written.
bool stoppedDuringStartUp(const rgbdmap::RunControl& control) {
  if (!control.stop.load()) return false;
  spdlog::info("stopped during start-up: nothing mapped, no map written");
  return true;
}

// How the command line names its options in a refusal (chooseRunMode).
rgbdmap::OptionNames commandLineNames(const CommandLine& o) {
  rgbdmap::OptionNames names;
  names.out = "--out";
  names.localise = "--localise " + o.localise;
  names.continue_from = "--continue " + o.continue_from;
  names.mesh = "--mesh";
  names.grid = "--grid";
  names.octomap = "--octomap";
  names.key = [](const std::string& key) { return key; };
  names.set = [](const std::string& key, const std::string& value) {
    return "--set " + key + "=" + value;
  };
  return names;
}

int runMapping(const CommandLine& o, rgbdmap::RunControl& control, rgbdmap::RunSignals& signals) {
  using namespace rgbdmap;
  Config config;
  if (o.list_keys) {
    // --markdown: docs/configuration.md's table, so the reference cannot drift from the code.
    std::printf("%s", listKeys(config.keys(), o.markdown).c_str());
    return 0;
  }
  if (o.source.empty()) {
    spdlog::error("no --source given ({}); `rgbdmap synth --out DIR` makes a sequence to try",
                  rgbdmap::sourceUsage());
    return 2;
  }
  checkOutputFolder(o.out, "--out");
  if (!o.mesh.empty()) checkOutputFolder(o.mesh, "--mesh");
  if (!o.grid.empty()) checkOutputFolder(o.grid, "--grid");
  if (!o.octomap.empty()) checkOutputFolder(o.octomap, "--octomap");
  config.loadPreset(o.config_file.empty() ? presetForSource(o.source) : o.config_file);
  if (!o.rate.empty()) config.set("replay.rate", o.rate == "max" ? "0" : o.rate, "--rate");
  config.setAll(o.sets, "--set");
  // Mapping, or a saved session to start from: localised in (nothing mapped) or continued.
  const std::shared_ptr<const RunMode> mode = chooseRunMode(
      {o.out, o.localise, o.continue_from, !o.mesh.empty(), !o.grid.empty(), !o.octomap.empty()},
      config, commandLineNames(o));
  if (stoppedDuringStartUp(control)) return 0;
  std::unique_ptr<FrameSource> source = openSource(o.source, config);
  if (stoppedDuringStartUp(control)) return 0;
  config.pose.source = resolvePoseSource(
      config.pose.source, source->providesPoses(),
      source->describe() +
          ": has no ground truth poses; use --set pose.source=odometry or pose.source=trajectory");
  PipelineOutputs outputs = mode->outputs(o.out, o.mesh);
  outputs.grid_path = o.grid;
  outputs.octomap_path = o.octomap;
  outputs.status_line = !o.quiet;
  spdlog::info("configuration (preset {}):\n{}", config.preset, config.toYaml());

  if (!signals.runStarts({temporaryFiles(outputs)})) {
    stoppedDuringStartUp(control);
    return 0;
  }
  int code = 0;
  {
    const std::unique_ptr<Viewer> viewer = openRunViewer(o.viewer, control, o.out);
    if (viewer) outputs.publisher = &viewer->mailbox();
    Pipeline pipeline(config, std::move(source), outputs, mode);
    code = pipeline.run(control);
    if (!o.stats_file.empty()) {
      std::ofstream stats(o.stats_file);
      stats << pipeline.stats().toJson();
      if (!stats) spdlog::error("{}: cannot write statistics", o.stats_file);
    }
  }
  if (!o.no_render && mode->maps()) {
    std::string error;
    if (renderMapFile(o.out, outputs.trajectory_path, picturePathOf(o.out), {}, error))
      spdlog::info("picture of the map: {}", picturePathOf(o.out));
    else
      spdlog::warn("no picture of the map: {}", error);
  }
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  // Before any thread exists, so all inherit the mask (the `rgbdmap` launcher blocked the signals
  // before this program was even loaded: none can kill it during start-up).
  rgbdmap::RunSignals::block();
  rgbdmap::tuneAllocator();
  // spdlog creates its registry on first use: do it here, before any thread can log.
  spdlog::default_logger_raw();
  // SPDLOG_LEVEL=debug shows why loops and window alignments were or were not taken.
  spdlog::cfg::load_env_levels();
  rgbdmap::RunControl control;
  auto signals = std::make_unique<rgbdmap::RunSignals>(control);
  CLI::App app{"rgbdmap: real-time RGB-D dense mapping to a coloured point cloud (PCD)"};
  app.set_version_flag("--version", RGBDMAP_VERSION);
  CommandLine o;
  app.add_option("-c,--config", o.config_file,
                 "YAML config: a preset name (tum_fr1, kinect_v1, ...) or a file");
  app.add_option("-s,--source", o.source, rgbdmap::sourceUsage());
  app.add_option("-o,--out", o.out, "map file (PCD); checkpoints overwrite it atomically")
      ->capture_default_str();
  app.add_option("-r,--rate", o.rate,
                 "replay speed: 1 = as recorded, max = as fast as possible (lossless)");
  app.add_option("--set", o.sets, "override a config key: --set map.voxel_size=0.005 (repeatable)");
  app.add_option("--mesh", o.mesh,
                 "also write the map as a coloured triangle mesh (binary PLY), with every save");
  app.add_option("--grid", o.grid,
                 "also write a 2-D occupancy grid for ROS navigation (G.pgm and G.yaml, "
                 "map_server's format), with every save");
  app.add_option("--octomap", o.octomap,
                 "also write a binary OctoMap (.bt) of occupied and free space, with every save");
  app.add_option("--localise", o.localise,
                 "localise in a saved session (MAP.session) instead of mapping: every frame's "
                 "pose in its map's frame, written to OUT_trajectory.txt; the map is not changed");
  app.add_option("--continue", o.continue_from,
                 "go on mapping from a saved session (MAP.session): mapped in this run's own frame "
                 "until a saved place is recognised, then one map and one session with the saved "
                 "one's, written to --out (the saved map is not changed)")
      ->excludes("--localise");
  app.add_option("--stats", o.stats_file, "write counters and per-stage latency as JSON at exit");
  app.add_option("--viewer", o.viewer, "live window: auto (when a display is available) | none")
      ->check(CLI::IsMember({"auto", "none"}))
      ->capture_default_str();
  app.add_flag("--no-render", o.no_render, "do not write a picture of the map");
  app.add_flag("-q,--quiet", o.quiet, "no status line");
  CLI::Option* list_keys = app.add_flag("--list-keys", o.list_keys,
                                        "list every config key with its default and meaning");
  app.add_flag("--markdown", o.markdown,
               "with --list-keys: as the Markdown table of docs/configuration.md")
      ->needs(list_keys);

  rgbdmap::Command selected;
  rgbdmap::addRenderCommand(app, selected);
  rgbdmap::addAssociateCommand(app, selected);
  rgbdmap::addDevicesCommand(app, selected);
  rgbdmap::addRecordCommand(app, selected);
  rgbdmap::addSynthCommand(app, selected);
  rgbdmap::addEvaluateCommand(app, selected);
  rgbdmap::addViewCommand(app, selected);
  rgbdmap::addSessionCommand(app, selected);
  rgbdmap::addMergeCommand(app, selected);
  rgbdmap::addExportCommand(app, selected);
  rgbdmap::addCalibrateCommand(app, selected);
  app.require_subcommand(0, 1);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return rgbdmap::runGuarded([&] {
    if (!selected) return runMapping(o, control, *signals);
    // Other commands keep the default actions (Ctrl-C ends `synth` at once); `record` takes
    // the signals again with its own RunSignals.
    signals.reset();
    if (stoppedDuringStartUp(control)) return 0;
    rgbdmap::RunSignals::unblock();
    return selected();
  });
}
