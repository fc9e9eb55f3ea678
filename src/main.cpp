// rgbdmap: map a room with an RGB-D camera (or a TUM sequence replayed as one)
// into a coloured point cloud, checkpointed while it runs.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <thread>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/runtime/config.hpp"
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

// Signals are taken by one thread with sigwait, from the first instant of main (the `rgbdmap`
// launcher blocked them before this program was even loaded), so handlers never run inside the
// mapping code and no signal can kill the process during start-up.
// SIGUSR1: checkpoint now (during start-up there is nothing to write yet: a no-op).
// SIGINT/SIGTERM: stop; during start-up, before mapping begins; while mapping, drain and save.
// A second SIGINT: quit at once, removing the temporary file of a write in progress (the
// destination is never half-written).
class SignalThread {
 public:
  explicit SignalThread(rgbdmap::RunControl& control) : control_(control) {
    thread_ = std::thread([this] { run(); });
  }
  ~SignalThread() {
    done_.store(true);
    pthread_kill(thread_.native_handle(), SIGUSR1);  // wakes it now rather than at its timeout
    thread_.join();
  }
  // From here on SIGUSR1 asks the pipeline for a checkpoint of `map_path` and a stop drains and
  // saves. Returns false when a stop came first: then nothing is mapped. One lock orders the two,
  // so a stop during start-up never ends in a saved map (its message said none would be).
  bool mappingStarts(const std::string& map_path, const std::string& mesh_path = "") {
    std::lock_guard<std::mutex> lock(mutex_);
    if (control_.stop.load()) return false;
    map_path_ = map_path;
    mesh_path_ = mesh_path;
    mapping_ = true;
    return true;
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
      if (done_.load()) break;
      std::lock_guard<std::mutex> lock(mutex_);
      const bool mapping = mapping_;
      if (sig == SIGUSR1) {
        if (mapping) {
          spdlog::info("SIGUSR1: writing a checkpoint");
          control_.snapshot.store(true);
        } else {
          spdlog::info("SIGUSR1 during start-up: nothing mapped yet, no checkpoint");
        }
      } else if (sig == SIGINT || sig == SIGTERM) {
        if (control_.stop.exchange(true) && sig == SIGINT) {
          if (mapping) {
            std::remove((map_path_ + ".tmp-" + std::to_string(::getpid())).c_str());
            if (!mesh_path_.empty())
              std::remove((mesh_path_ + ".tmp-" + std::to_string(::getpid())).c_str());
            for (const char* trajectory : {"_keyframes.txt.tmp", "_trajectory.txt.tmp"})
              std::remove((stem(map_path_) + trajectory).c_str());
          }
          std::fputs("\nsecond interrupt: quitting without the final save\n", stderr);
          std::_Exit(130);
        }
        const char* name = sig == SIGINT ? "SIGINT" : "SIGTERM";
        if (mapping)
          spdlog::info("{}: stopping (interrupt again to quit without saving)", name);
        else
          spdlog::info("{} during start-up: stopping before mapping begins", name);
      }
    }
  }

  rgbdmap::RunControl& control_;
  std::mutex mutex_;  // orders mappingStarts() and the handling of a signal
  std::string map_path_;
  std::string mesh_path_;
  bool mapping_ = false;
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
  std::string mesh;
  std::string viewer = "auto";
  bool no_render = false;
  bool quiet = false;
  bool list_keys = false;
  bool markdown = false;
};

// The map's folder is created if missing and must be writable: better to refuse at once than to
// find out at the first checkpoint, after mapping for a while.
void checkOutputFolder(const std::string& map_path, const std::string& option = "--out") {
  namespace fs = std::filesystem;
  const fs::path folder = fs::path(map_path).parent_path();
  if (folder.empty()) return;
  std::error_code ec;
  if (!fs::is_directory(folder, ec) && !fs::create_directories(folder, ec))
    throw rgbdmap::InputError(option + " " + map_path + ": cannot create the folder " +
                              folder.string() + (ec ? " (" + ec.message() + ")" : ""));
  if (::access(folder.c_str(), W_OK) != 0)
    throw rgbdmap::InputError(option + " " + map_path + ": the folder " + folder.string() +
                              " is not writable");
}

// A stop requested before mapping began: nothing was mapped and nothing is written.
bool stoppedDuringStartUp(const rgbdmap::RunControl& control) {
  if (!control.stop.load()) return false;
  spdlog::info("stopped during start-up: nothing mapped, no map written");
  return true;
}

int runMapping(const MapOptions& o, rgbdmap::RunControl& control, SignalThread& signals) {
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
  checkOutputFolder(o.out);
  if (!o.mesh.empty()) checkOutputFolder(o.mesh, "--mesh");
  config.loadPreset(o.config_file.empty() ? presetForSource(o.source) : o.config_file);
  if (!o.rate.empty()) config.set("replay.rate", o.rate == "max" ? "0" : o.rate, "--rate");
  for (const std::string& s : o.sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos) throw InputError("--set " + s + ": expected key=value");
    config.set(s.substr(0, eq), s.substr(eq + 1), "--set");
  }
  if (stoppedDuringStartUp(control)) return 0;
  std::unique_ptr<FrameSource> source = openSource(o.source, config);
  if (stoppedDuringStartUp(control)) return 0;
  if (config.pose.source == "auto")
    config.pose.source = source->providesPoses() ? "groundtruth" : "odometry";
  if (config.pose.source == "groundtruth" && !source->providesPoses())
    throw InputError(
        source->describe() +
        ": has no ground truth poses; use --set pose.source=odometry or pose.source=trajectory");

  PipelineOutputs outputs;
  outputs.map_path = o.out;
  outputs.trajectory_path = stem(o.out) + "_keyframes.txt";
  outputs.frame_trajectory_path = stem(o.out) + "_trajectory.txt";
  outputs.config_path = stem(o.out) + ".yaml";
  outputs.mesh_path = o.mesh;
  outputs.status_line = !o.quiet;
  spdlog::info("configuration (preset {}):\n{}", config.preset, config.toYaml());

  if (!signals.mappingStarts(o.out, o.mesh)) {
    stoppedDuringStartUp(control);
    return 0;
  }
  int code = 0;
  {
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
  // A file-size limit (ulimit -f) must fail the write with EFBIG, reported like a full disk,
  // instead of killing the process.
  std::signal(SIGXFSZ, SIG_IGN);
  // spdlog creates its registry on first use: do it here, before any thread can log.
  spdlog::default_logger_raw();
  rgbdmap::RunControl control;
  auto signals = std::make_unique<SignalThread>(control);
  CLI::App app{"rgbdmap: real-time RGB-D dense mapping to a coloured point cloud (PCD)"};
  app.set_version_flag("--version", RGBDMAP_VERSION);
  MapOptions o;
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
  app.require_subcommand(0, 1);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (!selected) return runMapping(o, control, *signals);
    signals.reset();
    if (stoppedDuringStartUp(control)) return 0;
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
