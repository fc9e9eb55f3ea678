#include "rgbdmap/runtime/pipeline.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <mutex>

#include "rgbdmap/capture/depth_registration.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/runtime/capture_thread.hpp"
#include "rgbdmap/runtime/checkpoint_writer.hpp"
#include "rgbdmap/runtime/frame_queue.hpp"
#include "rgbdmap/runtime/frame_tracker.hpp"
#include "rgbdmap/runtime/fusion_thread.hpp"
#include "rgbdmap/runtime/run_mode.hpp"
#include "rgbdmap/runtime/status_line.hpp"
#include "rgbdmap/runtime/tracking_thread.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/slam/loop_closer.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {
namespace {

using Clock = std::chrono::steady_clock;

// Keyframes that may wait for fusion (the pool holds two more: one being fused, one spare). A few
// absorb a burst (a fast turn) while fusion catches up; more would only let the map lag further
// behind tracking (each slot holds a 640x480 frame).
constexpr std::size_t kFusionSlots = 4;

// Remembers the first fatal error of any thread.
class FirstError {
 public:
  void set(const std::string& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (message_.empty()) message_ = message;
  }
  std::string get() {
    std::lock_guard<std::mutex> lock(mutex_);
    return message_;
  }

 private:
  std::mutex mutex_;
  std::string message_;
};

// The configuration the run's parts are built with (and the effective configuration written):
// the source's camera, and the fusion threads resolved. Made once, before any thread starts;
// nothing changes it afterwards.
Config forSource(Config config, const FrameSource& source) {
  static_cast<CameraIntrinsics&>(config.camera) = source.intrinsics();
  // A live camera leaves the other cores to tracking; a replay is limited by fusion alone.
  if (config.map.fusion_threads == 0)
    config.map.fusion_threads = source.isLive() ? 1 : WorkerPool::resolve(0);
  return config;
}

// The trajectories written with every checkpoint: keyframes (from the fusion side) and every frame
// (from the tracking side), streamed to their files rather than held (null when not asked for).
struct Trajectories {
  std::shared_ptr<TrajectoryStream> keyframes, frames;
  std::vector<CheckpointWriter::TrajectoryFile> files;  // those asked for
};

Trajectories trajectoriesOf(const PipelineOutputs& outputs, const PoseCorrections* corrections) {
  Trajectories t;
  const auto streamTo = [corrections](const std::string& path) {
    return path.empty() ? nullptr : std::make_shared<TrajectoryStream>(path, corrections);
  };
  t.keyframes = streamTo(outputs.trajectory_path);
  t.frames = streamTo(outputs.frame_trajectory_path);
  for (const auto& file : {t.keyframes, t.frames})
    if (file) t.files.push_back(file);
  return t;
}

// The effective configuration, written beside the map before mapping (and into every session);
// says when no session is saved although one would be.
std::string writeConfiguration(Config& config, const PipelineOutputs& outputs,
                               const RunStats& stats) {
  const std::string configuration = config.toYaml();
  if (!outputs.config_path.empty()) std::ofstream(outputs.config_path) << configuration;
  if (!stats.loop_closure && config.checkpoint.session && !outputs.session_path.empty())
    spdlog::info(
        "session: not saved (it is made of loop closure's places and graph; loop "
        "closure is off)");
  return configuration;
}

// The mesh written with a checkpoint (--mesh), extracted now on the fusion thread (the TSDF
// changes with the next keyframe); none without --mesh.
CheckpointWriter::MeshFile meshFile(const PipelineOutputs& outputs, const Mapper& mapper,
                                    RunStats& stats) {
  if (outputs.mesh_path.empty()) return {};
  const auto start = std::chrono::steady_clock::now();
  std::shared_ptr<const TriangleMesh> mesh = mapper.meshSnapshot();
  stats.mesh_extract_latency.record(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return {std::move(mesh), outputs.mesh_path};
}

// The occupancy grid written with a checkpoint (--grid): what the map says about up so far, taken
// on the fusion thread; the writer finds the floor and draws the grid.
CheckpointWriter::GridFile gridFile(const PipelineOutputs& outputs, const Mapper& mapper,
                                    const Config& config) {
  if (outputs.grid_path.empty()) return {};
  return {outputs.grid_path, mapper.upEvidence(), config.up, config.grid};
}

// The OctoMap written with a checkpoint (--octomap): the free space seen so far, copied on the
// fusion thread.
CheckpointWriter::OctomapFile octomapFile(const PipelineOutputs& outputs, const Mapper& mapper) {
  if (outputs.octomap_path.empty()) return {};
  return {mapper.freeSpaceSnapshot(), outputs.octomap_path};
}

// The session saved with a checkpoint (MAP.session/, with loop closure unless
// checkpoint.session=false): the kept keyframes taken on the fusion thread (their images shared,
// not copied); the graph and places as they are when the writer gets to them.
CheckpointWriter::SessionFile sessionFile(const PipelineOutputs& outputs, const Mapper& mapper,
                                          const LoopCloser* loop_closer,
                                          const Trajectories& trajectories, const Config& config,
                                          const std::string& configuration) {
  if (outputs.session_path.empty() || !loop_closer || !config.checkpoint.session) return {};
  // Continuing, until the run joins the saved map: its graph would hold two unrelated frames.
  if (mapper.awaitingJoin()) return {};
  auto session = std::make_shared<Session>();
  session->created_by = std::string("rgbdmap ") + RGBDMAP_VERSION;
  session->camera = config.camera;
  session->configuration = configuration;
  session->live_graph = loop_closer;
  session->keyframes = mapper.keptKeyframes().entries();
  // The writer persists the trajectories before the session: their spools are whole by then.
  if (trajectories.frames) session->frames_spool = trajectories.frames->spool();
  if (trajectories.keyframes) session->fused_spool = trajectories.keyframes->spool();
  return {std::move(session), outputs.session_path};
}

// Counts and logs every write of the checkpoint writer (on its thread); where up and the floor
// came from is logged the first time and whenever it changes.
CheckpointWriter::Callback reportWrites(RunStats& stats, const std::string& mesh_path,
                                        const std::string& grid_path) {
  auto last_sources = std::make_shared<std::string>();
  return [&stats, mesh_path, grid_path, last_sources](const CheckpointWriter::Result& r) {
    if (!r.ground_sources.empty() && r.ground_sources != *last_sources) {
      spdlog::info("grid: {}", r.ground);
      *last_sources = r.ground_sources;
    }
    if (r.grid) {
      stats.grid_write_latency.record(r.grid_seconds);
      spdlog::info("grid: {}x{} cells of {:.2f} m ({} occupied, {} free) written to {} in {:.2f} s",
                   r.grid->width, r.grid->height, r.grid->resolution,
                   r.grid->count(OccupancyGrid::kOccupied), r.grid->count(OccupancyGrid::kFree),
                   grid_path, r.grid_seconds);
    }
    if (!r.octomap_path.empty()) {
      stats.octomap_write_latency.record(r.octomap_seconds);
      spdlog::info("octomap: {} occupied and {} free leaves written to {} in {:.2f} s",
                   r.octomap_occupied, r.octomap_free, r.octomap_path, r.octomap_seconds);
    }
    if (r.mesh_seconds > 0.0) stats.mesh_write_latency.record(r.mesh_seconds);
    if (r.ok && !mesh_path.empty()) {
      stats.mesh_triangles.store(r.mesh_triangles);
      spdlog::info("mesh: {} triangles written to {} in {:.2f} s", r.mesh_triangles, mesh_path,
                   r.mesh_seconds);
    }
    if (!r.session_path.empty())
      spdlog::info(
          "session: {:.1f} MB written to {} in {:.2f} s ({:.1f} MB of new images and places)",
          static_cast<double>(r.session_bytes) / (1024.0 * 1024.0), r.session_path,
          r.session_seconds, static_cast<double>(r.session_appended) / (1024.0 * 1024.0));
    if (!r.store_path.empty()) {
      stats.store_write_latency.record(r.store_seconds);
      stats.store_bytes_written.fetch_add(r.store.bytes);
    }
    if (r.ok) {
      stats.checkpoints_written.fetch_add(1);
      if (!r.path.empty())
        spdlog::info("checkpoint: {} points written to {} in {:.2f} s", r.points, r.path,
                     r.seconds);
      else if (!r.store_path.empty())
        spdlog::info(
            "checkpoint: {} points, {} of {} cells changed ({} gone), {:.1f} MB written to {} in "
            "{:.2f} s",
            r.points, r.store.changed, r.store.cells, r.store.removed,
            static_cast<double>(r.store.bytes) / (1024.0 * 1024.0), r.store_path, r.seconds);
      else  // localising: the trajectories alone
        spdlog::info("checkpoint: trajectories written in {:.2f} s", r.seconds);
    } else {
      stats.checkpoints_failed.fetch_add(1);
      spdlog::error("checkpoint failed, mapping goes on: {}", r.error);
    }
  };
}

// The final save, through the writer so it is ordered after any checkpoint in flight, and the
// memory the run ended with. Returns 1 when the map could not be written, else 0.
int saveFinalMap(const Mapper& mapper, CheckpointWriter& writer,
                 const std::vector<CheckpointWriter::TrajectoryFile>& trajectory_files,
                 MapPublication& publication, const PipelineOutputs& outputs, const Config& config,
                 CheckpointWriter::SessionFile session, RunStats& stats) {
  const std::shared_ptr<const MapCloud> final_map = mapper.snapshot();
  writer.submit(final_map, outputs.map_path, trajectory_files, meshFile(outputs, mapper, stats),
                gridFile(outputs, mapper, config), octomapFile(outputs, mapper),
                std::move(session));
  publication.atEnd(final_map, mapper.upEvidence());
  const CheckpointWriter::Result final_write = writer.flush();
  int exit_code = 0;
  if (!final_write.ok) {
    spdlog::error("final map not saved: {}", final_write.error);
    exit_code = 1;
  } else if (!final_write.path.empty()) {
    spdlog::info("map: {} points written to {}", final_write.points, final_write.path);
  }
  stats.ground = final_write.ground;
  stats.peak_rss_mb = peakRssMb();
  stats.kept_keyframes_mb =
      static_cast<double>(mapper.keptKeyframes().memoryBytes()) / (1024.0 * 1024.0);
  stats.kept_keyframes_on_disk = mapper.keptKeyframes().onDisk();
  stats.kept_keyframes_disk_mb =
      static_cast<double>(mapper.keptKeyframes().diskBytes()) / (1024.0 * 1024.0);
  stats.map_memory_mb = static_cast<double>(mapper.memoryBytes()) / (1024.0 * 1024.0);
  stats.map_blocks_on_disk = mapper.blocksOnDisk();
  stats.map_disk_mb = static_cast<double>(mapper.mapDiskBytes()) / (1024.0 * 1024.0);
  stats.place_database_mb = static_cast<double>(stats.place_bytes.load()) / (1024.0 * 1024.0);
  return exit_code;
}

}  // namespace

Pipeline::Pipeline(Config config, std::unique_ptr<FrameSource> source, PipelineOutputs outputs,
                   std::shared_ptr<const RunMode> mode)
    : config_(std::move(config)),
      source_(std::move(source)),
      outputs_(std::move(outputs)),
      mode_(std::move(mode)) {}

int Pipeline::run(RunControl& control) {
  Config config = forSource(config_, *source_);
  const CameraIntrinsics camera = config.camera;
  const bool live = source_->isLive();
  // The loop thread, as the run's mode makes it (loop closure, the localiser or none): the
  // corrections it publishes move the trajectories, and the map follows them (Mapper).
  LoopThread loop = mode_->startLoopThread(config, stats_, !live);
  stats_.loop_closure = loop.loop_closer != nullptr;
  stats_.localising = !mode_->maps();
  GraphAttachment graph_attachment(outputs_.publisher, loop.loop_closer.get(), camera);
  const Trajectories trajectories = trajectoriesOf(outputs_, loop.corrections.get());
  mode_->startTrajectories(trajectories.frames.get(), trajectories.keyframes.get());
  FrameTracker tracker(
      mode_->keyframeSelector(config),
      makePoseProvider(config.pose, config.tracking, config.camera, config.filter.min_depth,
                       config.filter.max_depth, loop.keyframeSink()),
      stats_, trajectories.frames.get());
  Mapper mapper(config.camera, config.filter, config.map, config.refusion, stats_,
                loop.corrections.get(), trajectories.keyframes.get());
  mapper.keepMeshes(!outputs_.mesh_path.empty());
  if (!outputs_.octomap_path.empty()) mapper.keepFreeSpace(config.octomap);
  mode_->startMap(mapper);
  spdlog::info("source: {}", source_->describe());
  spdlog::info("{}", mode_->describe(tracker.poses().describe(), config, loop));
  const std::string configuration = writeConfiguration(config, outputs_, stats_);

  FrameQueue queue(static_cast<std::size_t>(config.queue.capacity),
                   live ? QueuePolicy::kDropOldest : QueuePolicy::kBlock, camera.width,
                   camera.height);
  CheckpointWriter writer(reportWrites(stats_, outputs_.mesh_path, outputs_.grid_path),
                          config.checkpoint.store ? outputs_.store_path : "");
  FirstError error;
  const auto fail = [&error, &control](const std::string& message) {
    error.set(message);
    control.stop.store(true);
  };
  const Clock::time_point start = Clock::now();

  // The threads: capture -> queue -> tracking -> fusion (-> writer), the status line here.
  std::unique_ptr<DepthRegistration> registration;
  if (!config.camera.depthRegistered()) {
    registration = std::make_unique<DepthRegistration>(config.camera);
    const Eigen::Vector3d t = registration->colorFromDepth().translation();
    spdlog::info(
        "depth: its own camera, registered to colour on capture (at ({:.4f}, {:.4f}, {:.4f}) m "
        "and {:.3f} deg from the colour camera)",
        t.x(), t.y(), t.z(),
        Eigen::AngleAxisd(registration->colorFromDepth().linear()).angle() * 180.0 / M_PI);
  }
  CaptureThread capture(*source_, queue, stats_, control, fail, registration.get());
  // Declared before the fusion thread, which serves its map requests.
  MapPublication publication(outputs_.publisher);
  FusionThread fusion(mapper, kFusionSlots, camera.width, camera.height, fail);
  // Checkpoints: the fusion thread takes the map snapshot and hands it to the writer, which
  // writes the trajectories recorded so far beside it. With a map store, the PCD is written when
  // asked for (and at the end); the store takes what changed at every checkpoint.
  auto checkpoint = [&](bool asked) {
    const std::string pcd = asked || !writer.hasStore() ? outputs_.map_path : "";
    fusion.request(MapRequest::kCheckpoint, [&, pcd](const Mapper& m) {
      writer.submit(
          m.snapshot(), pcd, trajectories.files, meshFile(outputs_, m, stats_),
          gridFile(outputs_, m, config), octomapFile(outputs_, m),
          sessionFile(outputs_, m, loop.loop_closer.get(), trajectories, config, configuration));
    });
  };
  // Tracking never waits for fusion, except in a lossless replay, where waiting keeps the set of
  // keyframes (and so the map) independent of timing.
  TrackingThread::Parts parts{queue,
                              tracker,
                              fusion,
                              publication,
                              loop.shownPoses(outputs_.publisher != nullptr),
                              loop.before_placement.get()};
  if (!live && loop.loop_closer) {
    // The local window moves the newest keyframes at every keyframe: fused at whatever the loop
    // thread had reached, a replay's map would differ from run to run.
    parts.settled_corrections = [&loop]() -> FusionThread::Settled {
      LoopCloser* closer = loop.loop_closer.get();
      const std::uint64_t added = closer->keyframesAdded();
      return [closer, added] { return closer->settledAfter(added); };
    };
  }
  TrackingThread tracking(parts, !live, config.checkpoint, checkpoint, stats_, control, fail);

  // Wait: status until the tracking thread has taken every frame, then the rest in turn.
  StatusLine status(stats_, queue, outputs_.status_line, start);
  status.showUntil([&tracking] { return tracking.done(); }, control.stop);
  capture.join();
  tracking.join();
  if (const std::string report = tracker.poses().report(); !report.empty())
    spdlog::info("tracking: {}", report);
  queue.freeImages();
  loop.finish();
  if (fusion.queued() > 0) spdlog::info("fusing the last {} keyframes", fusion.queued());
  fusion.finish();
  stats_.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  stats_.frames_dropped.store(queue.dropped());
  stats_.queue_depth.store(0);
  status.showFinal(stats_.wall_seconds);

  // Finish: the final map (at the final corrections: re-fused if the last loops moved kept
  // keyframes), then the exit code the run's mode calls for.
  mapper.settle();
  int exit_code = saveFinalMap(
      mapper, writer, trajectories.files, publication, outputs_, config,
      sessionFile(outputs_, mapper, loop.loop_closer.get(), trajectories, config, configuration),
      stats_);
  // No keyframe comes any more and the session is saved: the places can go.
  graph_attachment.release();
  if (loop.loop_closer) loop.loop_closer->forgetPlaces();
  const std::string fatal = error.get();
  if (!fatal.empty()) {
    spdlog::error("{}", fatal);
    exit_code = 1;
  }
  const bool stopped_on_request = control.stop.load() && fatal.empty();
  return std::max(exit_code, mode_->end(loop, stats_, source_->skipReasons(), stopped_on_request));
}

}  // namespace rgbdmap
