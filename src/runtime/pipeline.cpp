#include "rgbdmap/runtime/pipeline.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <thread>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/mapping/frame_tracker.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/runtime/checkpoint_writer.hpp"
#include "rgbdmap/runtime/frame_queue.hpp"
#include "rgbdmap/runtime/fusion_thread.hpp"
#include "rgbdmap/runtime/unmapped_frames.hpp"
#include "rgbdmap/slam/loop_closer.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {
namespace {

using Clock = std::chrono::steady_clock;

// Keyframes that may wait for fusion (the pool holds two more: one being fused, one spare). A few
// absorb a burst (a fast turn) while fusion catches up; more would only let the map lag further
// behind tracking (each slot holds a 640x480 frame).
constexpr std::size_t kFusionSlots = 4;

double now() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

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

// " | loops N" while loop closure runs (the status line says when a loop closed).
std::string loops(const RunStats& s) {
  if (!s.loop_closure) return "";
  return " | loops " + std::to_string(s.loops_accepted.load());
}

std::string statusLine(const RunStats& s, double elapsed) {
  char line[256];
  std::snprintf(line, sizeof line,
                "frames %llu read, %llu dropped, %llu skipped | %.1f fps | keyframes %llu | map "
                "%llu points | queue %llu%s%s",
                static_cast<unsigned long long>(s.frames_captured.load()),
                static_cast<unsigned long long>(s.frames_dropped.load()),
                static_cast<unsigned long long>(s.frames_skipped.load()),
                elapsed > 0 ? static_cast<double>(s.frames_processed.load()) / elapsed : 0.0,
                static_cast<unsigned long long>(s.keyframes.load()),
                static_cast<unsigned long long>(s.map_points.load()),
                static_cast<unsigned long long>(s.queue_depth.load()), loops(s).c_str(),
                s.tracking_lost.load() ? " | tracking lost" : "");
  return line;
}

// A trajectory file streamed as it is recorded (null when not asked for).
std::shared_ptr<TrajectoryStream> streamTo(const std::string& path,
                                           const PoseCorrections* corrections) {
  return path.empty() ? nullptr : std::make_shared<TrajectoryStream>(path, corrections);
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

}  // namespace

Pipeline::Pipeline(Config config, std::unique_ptr<FrameSource> source, PipelineOutputs outputs)
    : config_(std::move(config)), source_(std::move(source)), outputs_(std::move(outputs)) {}

int Pipeline::run(RunControl& control) {
  const CameraIntrinsics camera = source_->intrinsics();
  static_cast<CameraIntrinsics&>(config_.camera) = camera;
  // A live camera leaves the other cores to tracking; a replay is limited by fusion alone.
  if (config_.map.fusion_threads == 0)
    config_.map.fusion_threads = source_->isLive() ? 1 : WorkerPool::resolve(0);
  // Loop closure needs a tracker with keyframes (the dense one); the corrections it publishes
  // move the trajectories and the map's submaps.
  stats_.loop_closure = config_.loop.enabled && tracksKeyframes(config_.pose, config_.tracking);
  std::unique_ptr<PoseCorrections> corrections;
  std::unique_ptr<LoopCloser> loop_closer;
  if (stats_.loop_closure) {
    corrections = std::make_unique<PoseCorrections>();
    loop_closer = std::make_unique<LoopCloser>(config_.camera, config_.tracking, config_.loop,
                                               config_.filter.min_depth, config_.filter.max_depth,
                                               *corrections, stats_, !source_->isLive());
  }
  // The trajectories written with every checkpoint: keyframes (from the fusion side) and every
  // frame (from the tracking side), streamed to their files rather than held.
  const std::shared_ptr<TrajectoryStream> keyframe_file =
      streamTo(outputs_.trajectory_path, corrections.get());
  const std::shared_ptr<TrajectoryStream> frame_file =
      streamTo(outputs_.frame_trajectory_path, corrections.get());
  std::vector<CheckpointWriter::TrajectoryFile> trajectory_files;
  for (const auto& file : {keyframe_file, frame_file})
    if (file) trajectory_files.push_back(file);
  FrameTracker tracker(
      makeKeyframeSelector(config_.keyframe, config_.pose),
      makePoseProvider(config_.pose, config_.tracking, config_.camera, config_.filter.min_depth,
                       config_.filter.max_depth, loop_closer.get()),
      stats_, frame_file.get());
  Mapper mapper(config_.camera, config_.filter, config_.map, config_.submaps, stats_,
                corrections.get(), keyframe_file.get());
  if (!outputs_.mesh_path.empty()) mapper.keepMeshes();
  spdlog::info("source: {}", source_->describe());
  spdlog::info("poses: {}, keyframes: {}, loop closure: {}", tracker.poses().describe(),
               effectiveKeyframePolicy(config_.keyframe, config_.pose),
               stats_.loop_closure ? "on" : "off");
  if (!outputs_.config_path.empty()) {
    std::ofstream(outputs_.config_path) << config_.toYaml();
  }

  FrameQueue queue(static_cast<std::size_t>(config_.queue.capacity),
                   source_->isLive() ? QueuePolicy::kDropOldest : QueuePolicy::kBlock, camera.width,
                   camera.height);
  CheckpointWriter writer([this](const CheckpointWriter::Result& r) {
    if (r.mesh_seconds > 0.0) stats_.mesh_write_latency.record(r.mesh_seconds);
    if (r.ok && !outputs_.mesh_path.empty()) {
      stats_.mesh_triangles.store(r.mesh_triangles);
      spdlog::info("mesh: {} triangles written to {} in {:.2f} s", r.mesh_triangles,
                   outputs_.mesh_path, r.mesh_seconds);
    }
    if (r.ok) {
      stats_.checkpoints_written.fetch_add(1);
      spdlog::info("checkpoint: {} points written to {} in {:.2f} s", r.points, r.path, r.seconds);
    } else {
      stats_.checkpoints_failed.fetch_add(1);
      spdlog::error("checkpoint failed, mapping goes on: {}", r.error);
    }
  });
  FirstError error;
  const Clock::time_point start = Clock::now();

  std::thread capture([&] {
    try {
      Frame* frame = nullptr;
      std::uint64_t index = 0;
      std::uint64_t index_at_outage_checkpoint = 0;
      while (!control.stop.load()) {
        if (!frame && !(frame = queue.acquire())) break;
        const auto read_start = Clock::now();
        const ReadStatus status = source_->read(*frame);
        if (status == ReadStatus::kEnd) break;
        if (status == ReadStatus::kSkipped) {
          stats_.frames_skipped.store(source_->skipped());
          continue;  // keep the slot for the next read
        }
        if (status == ReadStatus::kTimeout) {
          if (!source_->canReconnect())
            throw InputError(source_->describe() + ": camera stopped delivering frames");
          // Keep everything mapped: checkpoint now, then wait for the same camera. A camera
          // that reopens but delivers nothing does not rewrite an unchanged map every cycle.
          stats_.disconnects.fetch_add(1);
          const bool new_frames = index != index_at_outage_checkpoint;
          if (new_frames) control.snapshot.store(true);
          index_at_outage_checkpoint = index;
          spdlog::warn(
              "{}: camera stopped delivering frames; {}, waiting for it to come back (Ctrl-C "
              "saves and quits)",
              source_->describe(),
              new_frames ? "map checkpointed" : "no new frame since the last checkpoint");
          while (!control.stop.load() && !source_->reconnect()) {
          }
          if (!control.stop.load())
            spdlog::info("{}: camera is back, mapping resumes", source_->describe());
          continue;
        }
        stats_.read_latency.record(
            std::chrono::duration<double>(Clock::now() - read_start).count());
        frame->index = index++;
        frame->captured_at = now();
        stats_.frames_captured.fetch_add(1);
        queue.push(frame);
        frame = nullptr;
        stats_.frames_dropped.store(queue.dropped());
      }
      // A frame still held here stays in the pool's storage; only the mapper returns frames.
    } catch (const std::exception& e) {
      error.set(e.what());
      control.stop.store(true);
    }
    stats_.frames_skipped.store(source_->skipped());
    queue.close();
  });

  // Declared before the fusion thread, which serves its map requests.
  MapPublication publication(outputs_.publisher);
  // Keyframes go to the fusion thread; tracking never waits for fusion, except in a lossless
  // replay, where waiting keeps the set of keyframes (and so the map) independent of timing.
  const bool live = source_->isLive();
  FusionThread fusion(mapper, kFusionSlots, camera.width, camera.height,
                      [&](const std::string& message) {
                        error.set(message);
                        control.stop.store(true);
                      });
  // Checkpoints: the fusion thread takes the map snapshot and hands it to the writer, which
  // writes the trajectories recorded so far beside it.
  auto checkpoint = [&] {
    fusion.request(MapRequest::kCheckpoint, [this, &writer, &trajectory_files](const Mapper& m) {
      writer.submit(m.snapshot(), outputs_.map_path, trajectory_files,
                    meshFile(outputs_, m, stats_));
    });
  };

  std::atomic<bool> tracking_done{false};
  std::thread tracking([&] {
    double last_checkpoint = now();
    std::uint64_t keyframes_at_checkpoint = 0;
    bool finished = false;
    while (!finished) {
      // Frames may stop coming (camera unplugged), so wake up regularly for checkpoints.
      if (Frame* frame = queue.pop(std::chrono::milliseconds(100), finished)) {
        const auto track_start = Clock::now();
        stats_.queue_latency.record(now() - frame->captured_at);
        try {
          bool keyframe = false;
          if (tracker.track(*frame)) {
            keyframe = fusion.submit(*frame, !live);
            if (keyframe)
              tracker.acceptKeyframe(*frame);
            else
              stats_.keyframes_deferred.fetch_add(1, std::memory_order_relaxed);
          }
          // The viewer is shown the pose after loop closures, like the written trajectory.
          if (corrections && outputs_.publisher)
            frame->pose = corrections->snapshot().apply(frame->anchor, frame->pose);
          publication.afterFrame(*frame, tracker.state(), stats_, keyframe);
        } catch (const std::exception& e) {
          error.set(std::string(frame->origin) + ": " + e.what());
          control.stop.store(true);
        }
        queue.release(frame);
        stats_.frames_processed.fetch_add(1);
        stats_.track_latency.record(
            std::chrono::duration<double>(Clock::now() - track_start).count());
      }
      // Also while no frame comes (a camera paused, a bag played to its end): the subscriber
      // still gets the map with the last keyframes in it.
      if (publication.mapDue(stats_))
        fusion.request(MapRequest::kViewer,
                       [&publication](const Mapper& m) { publication.publishMap(m); });
      const std::uint64_t keyframes = tracker.keyframesAccepted();
      const bool by_count = config_.checkpoint.every_keyframes > 0 &&
                            keyframes - keyframes_at_checkpoint >=
                                static_cast<std::uint64_t>(config_.checkpoint.every_keyframes) &&
                            now() - last_checkpoint >= config_.checkpoint.min_seconds;
      const bool by_time = config_.checkpoint.every_seconds > 0 &&
                           now() - last_checkpoint >= config_.checkpoint.every_seconds &&
                           keyframes > keyframes_at_checkpoint;
      if (control.snapshot.exchange(false) || by_count || by_time) {
        checkpoint();
        keyframes_at_checkpoint = keyframes;
        last_checkpoint = now();
      }
    }
    // A snapshot request that came while the queue was draining is served by the final save.
    control.snapshot.store(false);
    tracking_done.store(true);
  });

  // Status until the tracking thread has taken every frame.
  const bool tty = outputs_.status_line && ::isatty(STDERR_FILENO);
  double last_print = 0;
  bool stop_announced = false;
  while (!tracking_done.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stats_.queue_depth.store(queue.depth());
    if (control.stop.load() && !stop_announced) {
      stop_announced = true;
      if (tty) std::fputc('\n', stderr);
      spdlog::info("stopping: draining {} queued frames, then saving", queue.depth());
    }
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (outputs_.status_line && elapsed - last_print >= (tty ? 0.25 : 5.0)) {
      last_print = elapsed;
      if (tty)
        std::fprintf(stderr, "\r%s\033[K", statusLine(stats_, elapsed).c_str());
      else
        spdlog::info("{}", statusLine(stats_, elapsed));
    }
  }
  capture.join();
  tracking.join();
  if (loop_closer) loop_closer->finish();  // every keyframe searched: final corrections
  if (fusion.queued() > 0) spdlog::info("fusing the last {} keyframes", fusion.queued());
  fusion.finish();
  stats_.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  stats_.frames_dropped.store(queue.dropped());
  stats_.queue_depth.store(0);
  if (tty) std::fprintf(stderr, "\r%s\033[K\n", statusLine(stats_, stats_.wall_seconds).c_str());

  // Final save, through the writer so it is ordered after any checkpoint in flight.
  const std::shared_ptr<const MapCloud> final_map = mapper.snapshot();
  writer.submit(final_map, outputs_.map_path, trajectory_files, meshFile(outputs_, mapper, stats_));
  publication.atEnd(final_map);
  const CheckpointWriter::Result final_write = writer.flush();
  int exit_code = 0;
  if (!final_write.ok) {
    spdlog::error("final map not saved: {}", final_write.error);
    exit_code = 1;
  } else {
    spdlog::info("map: {} points written to {}", final_write.points, final_write.path);
  }
  stats_.peak_rss_mb = peakRssMb();
  stats_.mesh_memory_mb = static_cast<double>(mapper.meshMemoryBytes()) / (1024.0 * 1024.0);
  stats_.map_memory_mb = static_cast<double>(mapper.memoryBytes()) / (1024.0 * 1024.0);
  const std::string fatal = error.get();
  if (!fatal.empty()) {
    spdlog::error("{}", fatal);
    exit_code = 1;
  }
  // Nothing mapped is a failure; most frames unused is worth saying.
  const bool stopped_on_request = control.stop.load() && fatal.empty();
  exit_code = std::max(
      exit_code, UnmappedFrames::of(stats_, source_->skipReasons()).report(stopped_on_request));
  return exit_code;
}

}  // namespace rgbdmap
