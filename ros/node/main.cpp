// rgbdmap_node: the rgbdmap pipeline as a ROS node. Subscribes to a camera's colour, depth and
// camera_info topics, publishes ~map, ~pose and TF, serves ~save_map and ~snapshot, and takes
// every config key as a private parameter. Signals, checkpoints and the exit are the CLI's:
// SIGUSR1 writes the map, SIGINT/SIGTERM stop with a final save (exit 0), a second SIGINT more
// than RunSignals::kSameInterrupt after the first quits.
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <spdlog/spdlog.h>
#include <std_srvs/Trigger.h>

#include <algorithm>
#include <fstream>
#include <thread>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/ros/node_params.hpp"
#include "rgbdmap/ros/ros_publisher.hpp"
#include "rgbdmap/ros/topic_source.hpp"
#include "rgbdmap/runtime/exit_code.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/runtime/pipeline.hpp"
#include "rgbdmap/runtime/pose_source.hpp"
#include "rgbdmap/runtime/run_mode.hpp"
#include "rgbdmap/runtime/run_signals.hpp"

namespace {

using namespace rgbdmap;

// ~save_map and ~snapshot: ask for a checkpoint as SIGUSR1 does, and answer once it is written
// (or failed), so that the caller can use the file at once.
// ~save_octomap answers the same way with the OctoMap (written with every save).
bool writeMapNow(RunControl& control, const RunStats& stats, const std::string& path,
                 std_srvs::Trigger::Response& response) {
  const auto done = [&] {
    return stats.checkpoints_written.load() + stats.checkpoints_failed.load();
  };
  const std::uint64_t before_written = stats.checkpoints_written.load();
  const std::uint64_t before = done();
  control.snapshot.store(true);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (done() == before && !control.stop.load() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  response.success = stats.checkpoints_written.load() > before_written;
  if (response.success)
    response.message = stats.localising
                           ? path
                           : path + " (" + std::to_string(stats.map_points.load()) + " points)";
  else if (control.stop.load())
    response.message = "stopping: the final save writes " + path;
  else
    response.message = "the checkpoint of " + path + " failed (see the node's log)";
  return true;
}

std::string withNodeCounts(const std::string& json, const TopicSource::Counts& c,
                           std::uint64_t maps, const SessionStream::Totals& session,
                           std::uint64_t session_dropped) {
  const auto brace = json.find_last_of('}');
  std::string out = json.substr(0, brace);
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  out += ",\n  \"ros\": {\"color_received\": " + std::to_string(c.color_received) +
         ", \"depth_received\": " + std::to_string(c.depth_received) +
         ", \"color_lost\": " + std::to_string(c.color_lost) +
         ", \"paired\": " + std::to_string(c.paired) +
         ", \"buffer_dropped\": " + std::to_string(c.buffer_dropped) +
         ", \"unmatched\": " + std::to_string(c.unmatched) +
         ", \"maps_published\": " + std::to_string(maps) +
         ", \"session_bytes\": " + std::to_string(session.bytes) +
         ", \"session_keyframes\": " + std::to_string(session.keyframes) +
         ", \"session_places\": " + std::to_string(session.places) +
         ", \"session_pieces\": " + std::to_string(session.pieces) +
         ", \"session_piece_bytes\": " + std::to_string(session.piece_bytes) +
         ", \"session_keyframes_dropped\": " + std::to_string(session_dropped) + "}\n}\n";
  return out;
}

// How the node names its parameters in a refusal (chooseRunMode): "parameter /rgbdmap/localise",
// and config keys as private parameters ("pose/source", set as _pose/source:=odometry).
OptionNames nodeNames(const ros::NodeHandle& pnh) {
  OptionNames names;
  names.out = "~out";
  names.localise = "parameter " + pnh.resolveName("localise");
  names.continue_from = "parameter " + pnh.resolveName("continue");
  names.grid = "~grid";
  names.octomap = "~octomap";
  names.key = [](std::string key) {
    std::replace(key.begin(), key.end(), '.', '/');
    return key;
  };
  names.set = [key = names.key](const std::string& k, const std::string& value) {
    return "_" + key(k) + ":=" + value;
  };
  return names;
}

// What the node publishes, and where: its frames (the camera's from its images unless given),
// how often, and the session stream (only a mapping run has one: localising adds nothing).
RosPublisher::Options publisherOptions(const NodeSettings& settings, const TopicSource& topics,
                                       const Config& config, const RunMode& mode) {
  RosPublisher::Options publish;
  publish.map_frame = settings.map_frame;
  publish.camera_frame = !settings.camera_frame.empty()  ? settings.camera_frame
                         : !topics.cameraFrame().empty() ? topics.cameraFrame()
                                                         : "camera_rgb_optical_frame";
  if (!publish.camera_frame.empty() && publish.camera_frame.front() == '/')
    publish.camera_frame.erase(0, 1);  // tf2 frame ids carry no leading slash
  publish.map_interval = settings.map_interval;
  publish.map_max_points = settings.map_max_points;
  publish.grid_interval = settings.grid_interval;
  publish.up = config.up;
  publish.grid = config.grid;
  publish.session.interval = mode.maps() ? settings.session_interval : 0.0;
  publish.session.stream.bytes_per_second = settings.session_rate;
  publish.session.lossless = settings.lossless;
  return publish;
}

// The node's services, on a queue and thread of their own: a call waits for its checkpoint
// without holding up the image callbacks. ~save_map and ~snapshot write `saved` (the map;
// localising, the trajectory alone), ~save_octomap the OctoMap, ~session/resend asks the session
// stream to send everything again.
class NodeServices {
 public:
  NodeServices(RunControl& control, const Pipeline& pipeline, RosPublisher& publisher,
               const std::string& saved, const std::string& octomap)
      : octomap_(octomap) {
    nh_.setCallbackQueue(&queue_);
    using Request = std_srvs::Trigger::Request;
    using Response = std_srvs::Trigger::Response;
    const auto save = [&control, &pipeline, saved](Request&, Response& response) {
      return writeMapNow(control, pipeline.stats(), saved, response);
    };
    save_map_ = nh_.advertiseService<Request, Response>("save_map", save);
    snapshot_ = nh_.advertiseService<Request, Response>("snapshot", save);
    save_octomap_ = nh_.advertiseService<Request, Response>(
        "save_octomap", [&control, &pipeline, octomap](Request&, Response& response) {
          writeMapNow(control, pipeline.stats(), octomap, response);
          if (response.success) response.message = octomap;
          return true;
        });
    if (SessionPublisher* session = publisher.session())
      resend_ = nh_.advertiseService<Request, Response>(
          "session/resend", [session](Request&, Response& response) {
            session->resend();
            response.success = true;
            response.message = "run " + std::to_string(session->run());
            return true;
          });
    spinner_.start();
  }
  // The services that write the map (and the OctoMap, when one is written).
  std::string describe() const {
    return save_map_.getService() + ", " + snapshot_.getService() +
           (octomap_.empty() ? "" : ", " + save_octomap_.getService());
  }
  void stop() { spinner_.stop(); }

 private:
  std::string octomap_;
  ros::CallbackQueue queue_;
  ros::NodeHandle nh_{"~"};
  ros::ServiceServer save_map_, snapshot_, save_octomap_, resend_;
  ros::AsyncSpinner spinner_{1, &queue_};
};

// What became of the camera's images, logged, and the run's statistics with the node's counts
// written to `stats_file` ("" = none).
void reportAtEnd(const TopicSource::Counts& counts, const RunStats& stats, RosPublisher& publisher,
                 const std::string& stats_file) {
  spdlog::info(
      "rgbdmap_node: {} colour images received ({} lost before the node), {} pairs, {} dropped "
      "by the node ({} in its buffer, {} in the queue), {} frames mapped, {} maps published",
      counts.color_received, counts.color_lost, counts.paired,
      counts.buffer_dropped + stats.frames_dropped.load(), counts.buffer_dropped,
      stats.frames_dropped.load(), stats.frames_processed.load(), publisher.mapsPublished());
  if (stats_file.empty()) return;
  std::ofstream out(stats_file);
  SessionPublisher* session = publisher.session();
  out << withNodeCounts(stats.toJson(), counts, publisher.mapsPublished(),
                        session ? session->totals() : SessionStream::Totals{},
                        session ? session->keyframesDropped() : 0);
  if (!out) spdlog::error("{}: cannot write statistics", stats_file);
}

int runNode(RunControl& control, RunSignals& signals) {
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const NodeSettings settings = readNodeSettings(pnh);
  Config config;
  config.loadPreset(settings.config);
  applyPrivateParams(pnh, config);
  checkOutputFolder(settings.out, "~out");
  // Chosen before waiting for the camera: a session that cannot be used stops the node at once.
  const std::shared_ptr<const RunMode> mode =
      chooseRunMode({settings.out, settings.localise, settings.continue_from, false,
                     !settings.grid.empty(), settings.octomap_given},
                    config, nodeNames(pnh));

  // Image callbacks on the global queue, one thread: the pairer sees messages in order.
  ros::AsyncSpinner image_spinner(1);
  auto source = std::make_unique<TopicSource>(nh, config, control.stop, settings.lossless);
  TopicSource& topics = *source;
  image_spinner.start();
  if (!topics.waitForCamera()) {
    spdlog::info("stopped before any image arrived: nothing mapped, no map written");
    topics.shutdown();
    return 0;
  }
  config.pose.source = resolvePoseSource(
      config.pose.source, topics.providesPoses(),
      "pose.source=groundtruth: a ROS camera has no ground truth; use odometry or trajectory");
  PipelineOutputs outputs = mode->outputs(settings.out, "");
  outputs.grid_path = settings.grid;
  outputs.octomap_path = settings.octomap;
  if (!signals.runStarts({temporaryFiles(outputs)})) {
    spdlog::info("stopped during start-up: nothing mapped, no map written");
    topics.shutdown();
    return 0;
  }

  const RosPublisher::Options publish = publisherOptions(settings, topics, config, *mode);
  RosPublisher publisher(pnh, publish);

  outputs.status_line = false;
  outputs.publisher = &publisher;
  spdlog::info("configuration (preset {}):\n{}", config.preset, config.toYaml());
  Pipeline pipeline(config, std::move(source), outputs, mode);

  NodeServices services(control, pipeline, publisher,
                        mode->maps() ? settings.out : outputs.frame_trajectory_path,
                        settings.octomap);
  // What the node publishes (localising: the pose alone) and the services that write the map.
  const std::string published =
      mode->maps()
          ? fmt::format("{}, {}, {} and {}", pnh.resolveName("map"), pnh.resolveName("map_changes"),
                        pnh.resolveName("grid"), pnh.resolveName("pose"))
          : pnh.resolveName("pose");
  spdlog::info("{}: publishing {}, TF {} -> {}{}", mode->name(), published, publish.map_frame,
               publish.camera_frame, mode->maps() ? "; services " + services.describe() : "");
  if (settings.lossless)
    spdlog::info(
        "lossless: every image is kept until mapped; {} says how far the node has got "
        "(rgbdmap-play waits for it)",
        pnh.resolveName("intake"));

  const int code = pipeline.run(control);
  topics.shutdown();
  publisher.finish();
  reportAtEnd(topics.counts(), pipeline.stats(), publisher, settings.stats);
  services.stop();
  image_spinner.stop();
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  // Before any thread exists, so that all inherit the mask: signals are taken by RunSignals'
  // thread, never by a handler inside ROS or mapping code. ROS's own SIGINT handler is off.
  RunSignals::block();
  tuneAllocator();
  spdlog::default_logger_raw();
  ros::init(argc, argv, "rgbdmap", ros::init_options::NoSigintHandler);
  RunControl control;
  int code = 0;
  {
    RunSignals signals(control);
    code = runGuarded([&] { return runNode(control, signals); });
  }
  ros::shutdown();
  return code;
}
