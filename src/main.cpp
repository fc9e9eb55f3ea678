// rgbdmap: map a room with an RGB-D camera (or a TUM sequence replayed as one)
// into a coloured point cloud, checkpointed while it runs.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <thread>

#include "rgbdmap/base/config.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/runtime/pipeline.hpp"
#include "rgbdmap/runtime/source_factory.hpp"
#include "rgbdmap/tools/commands.hpp"
#include "rgbdmap/tools/map_renderer.hpp"
#include "rgbdmap/tools/run_viewer.hpp"

namespace {

std::string stem(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  return (dot == std::string::npos || (slash != std::string::npos && dot < slash))
             ? path
             : path.substr(0, dot);
}

// Signals are taken by one thread with sigwait, so handlers never run inside
// the mapping code. SIGUSR1: checkpoint now. SIGINT/SIGTERM: stop, drain, save.
// A second SIGINT: quit at once, removing the temporary file of a write in
// progress (the destination is never half-written).
class SignalThread {
 public:
  SignalThread(rgbdmap::RunControl& control, std::string map_path)
      : control_(control), map_path_(std::move(map_path)) {
    thread_ = std::thread([this] { run(); });
  }
  ~SignalThread() {
    done_.store(true);
    thread_.join();
  }
  static void blockInThisThread() {
    sigset_t set = signals();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
  }
  // Subcommands other than mapping keep the default actions (Ctrl-C ends
  // `synth` at once).
  static void unblockInThisThread() {
    sigset_t set = signals();
    pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
  }

 private:
  static sigset_t signals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGUSR1);
    return set;
  }
  void run() {
    const sigset_t set = signals();
    const timespec timeout{0, 100 * 1000 * 1000};
    while (!done_.load()) {
      const int sig = sigtimedwait(&set, nullptr, &timeout);
      if (sig == SIGUSR1) {
        spdlog::info("SIGUSR1: writing a checkpoint");
        control_.snapshot.store(true);
      } else if (sig == SIGINT || sig == SIGTERM) {
        if (control_.stop.exchange(true) && sig == SIGINT) {
          std::remove((map_path_ + ".tmp-" + std::to_string(::getpid())).c_str());
          std::fputs("\nsecond interrupt: quitting without the final save\n", stderr);
          std::_Exit(130);
        }
        spdlog::info("{}: stopping (interrupt again to quit without saving)",
                     sig == SIGINT ? "SIGINT" : "SIGTERM");
      }
    }
  }

  rgbdmap::RunControl& control_;
  std::string map_path_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

struct MapOptions {
  std::string config_file;
  std::string source = "";
  std::string out = "map.pcd";
  std::string rate;
  std::vector<std::string> sets;
  std::string stats_file;
  std::string viewer = "auto";
  bool no_render = false;
  bool quiet = false;
  bool list_keys = false;
};

// The map's folder is created if missing and must be writable: better to refuse at once than to
// find out at the first checkpoint, after mapping for a while.
void checkOutputFolder(const std::string& map_path) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::path(map_path).parent_path();
  if (folder.empty()) return;
  std::error_code ec;
  if (!fs::is_directory(folder, ec) && !fs::create_directories(folder, ec))
    throw rgbdmap::InputError("--out " + map_path + ": cannot create the folder " +
                              folder.string() + (ec ? " (" + ec.message() + ")" : ""));
  if (::access(folder.c_str(), W_OK) != 0)
    throw rgbdmap::InputError("--out " + map_path + ": the folder " + folder.string() +
                              " is not writable");
}

int runMapping(const MapOptions& o) {
  using namespace rgbdmap;
  Config config;
  if (o.list_keys) {
    for (const Config::Key& k : config.keys())
      std::printf("%-28s %-12s %s\n", k.name.c_str(), k.get().c_str(), k.help.c_str());
    return 0;
  }
  if (o.source.empty()) {
    spdlog::error(
        "no --source given (tum:DIR, openni2, openni2:URI or openni2:FILE.oni); `rgbdmap synth "
        "--out DIR` makes a sequence to try");
    return 2;
  }
  checkOutputFolder(o.out);
  config.loadPreset(o.config_file.empty() ? presetForSource(o.source) : o.config_file);
  if (!o.rate.empty()) config.set("replay.rate", o.rate == "max" ? "0" : o.rate, "--rate");
  for (const std::string& s : o.sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos) throw InputError("--set " + s + ": expected key=value");
    config.set(s.substr(0, eq), s.substr(eq + 1), "--set");
  }
  std::unique_ptr<FrameSource> source = openSource(o.source, config);
  if (config.pose_source == "auto")
    config.pose_source = source->providesPoses() ? "groundtruth" : "odometry";
  if (config.pose_source == "groundtruth" && !source->providesPoses())
    throw InputError(
        source->describe() +
        ": has no ground truth poses; use --set pose.source=odometry or pose.source=trajectory");

  PipelineOutputs outputs;
  outputs.map_path = o.out;
  outputs.trajectory_path = stem(o.out) + "_keyframes.txt";
  outputs.config_path = stem(o.out) + ".yaml";
  outputs.status_line = !o.quiet;
  spdlog::info("configuration (preset {}):\n{}", config.preset, config.toYaml());

  RunControl control;
  int code = 0;
  {
    SignalThread signals(control, o.out);
    const std::unique_ptr<Viewer> viewer = openRunViewer(o.viewer, control, o.out);
    if (viewer) outputs.publisher = &viewer->mailbox();
    Pipeline pipeline(config, std::move(source), outputs);
    code = pipeline.run(control);
    if (!o.stats_file.empty()) {
      std::ofstream stats(o.stats_file);
      stats << pipeline.stats().toJson();
      if (!stats) spdlog::error("{}: cannot write statistics", o.stats_file);
    }
  }
  if (!o.no_render) {
    std::string error;
    if (renderMapFile(o.out, stem(o.out) + "_keyframes.txt", stem(o.out) + ".png", {}, error))
      spdlog::info("picture of the map: {}", stem(o.out) + ".png");
    else
      spdlog::warn("no picture of the map: {}", error);
  }
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  // Before any thread exists, so all inherit the mask.
  SignalThread::blockInThisThread();
  // spdlog creates its registry on first use: do it here, before any thread can log.
  spdlog::default_logger_raw();
  CLI::App app{"rgbdmap: real-time RGB-D dense mapping to a coloured point cloud (PCD)"};
  app.set_version_flag("--version", RGBDMAP_VERSION);
  MapOptions o;
  app.add_option("-c,--config", o.config_file,
                 "YAML config: a preset name (tum_fr1, kinect_v1, ...) or a file");
  app.add_option("-s,--source", o.source, "tum:DIR | openni2 | openni2:URI | openni2:FILE.oni");
  app.add_option("-o,--out", o.out, "map file (PCD); checkpoints overwrite it atomically")
      ->capture_default_str();
  app.add_option("-r,--rate", o.rate,
                 "replay speed: 1 = as recorded, max = as fast as possible (lossless)");
  app.add_option("--set", o.sets, "override a config key: --set map.voxel_size=0.005 (repeatable)");
  app.add_option("--stats", o.stats_file, "write counters and per-stage latency as JSON at exit");
  app.add_option("--viewer", o.viewer, "live window: auto (when a display is available) | none")
      ->check(CLI::IsMember({"auto", "none"}))
      ->capture_default_str();
  app.add_flag("--no-render", o.no_render, "do not write a picture of the map");
  app.add_flag("-q,--quiet", o.quiet, "no status line");
  app.add_flag("--list-keys", o.list_keys, "list every config key with its default and meaning");

  rgbdmap::Command selected;
  rgbdmap::addRenderCommand(app, selected);
  rgbdmap::addAssociateCommand(app, selected);
  rgbdmap::addDevicesCommand(app, selected);
  rgbdmap::addRecordCommand(app, selected);
  rgbdmap::addSynthCommand(app, selected);
  rgbdmap::addEvaluateCommand(app, selected);
  rgbdmap::addViewCommand(app, selected);
  app.require_subcommand(0, 1);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (!selected) return runMapping(o);
    SignalThread::unblockInThisThread();
    return selected();
  } catch (const rgbdmap::InputError& e) {
    spdlog::error("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
