#include "rgbdmap/runtime/pipeline.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <thread>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/runtime/checkpoint_writer.hpp"
#include "rgbdmap/runtime/frame_queue.hpp"

namespace rgbdmap {
namespace {

using Clock = std::chrono::steady_clock;

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

std::string statusLine(const RunStats& s, double elapsed) {
  char line[256];
  std::snprintf(line, sizeof line,
                "frames %llu read, %llu dropped, %llu skipped | %.1f fps | keyframes %llu | map "
                "%llu points | queue %llu",
                static_cast<unsigned long long>(s.frames_captured.load()),
                static_cast<unsigned long long>(s.frames_dropped.load()),
                static_cast<unsigned long long>(s.frames_skipped.load()),
                elapsed > 0 ? static_cast<double>(s.frames_processed.load()) / elapsed : 0.0,
                static_cast<unsigned long long>(s.keyframes.load()),
                static_cast<unsigned long long>(s.map_points.load()),
                static_cast<unsigned long long>(s.queue_depth.load()));
  return line;
}

}  // namespace

Pipeline::Pipeline(Config config, std::unique_ptr<FrameSource> source, PipelineOutputs outputs)
    : config_(std::move(config)), source_(std::move(source)), outputs_(std::move(outputs)) {}

int Pipeline::run(RunControl& control) {
  const CameraIntrinsics camera = source_->intrinsics();
  config_.camera = camera;
  Mapper mapper(config_, makePoseProvider(config_), stats_);
  spdlog::info("source: {}", source_->describe());
  spdlog::info("poses: {}", mapper.poses().describe());
  if (!outputs_.config_path.empty()) {
    std::ofstream(outputs_.config_path) << config_.toYaml();
  }

  FrameQueue queue(static_cast<std::size_t>(config_.queue_capacity),
                   source_->isLive() ? QueuePolicy::kDropOldest : QueuePolicy::kBlock, camera.width,
                   camera.height);
  CheckpointWriter writer([this](const CheckpointWriter::Result& r) {
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
          // Keep everything mapped: checkpoint now, then wait for the same camera.
          stats_.disconnects.fetch_add(1);
          control.snapshot.store(true);
          spdlog::warn(
              "{}: camera stopped delivering frames; map checkpointed, waiting for it "
              "to come back (Ctrl-C saves and quits)",
              source_->describe());
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

  std::atomic<bool> mapping_done{false};
  MapPublication publication(outputs_.publisher);
  std::thread mapping([&] {
    double last_checkpoint = now();
    std::uint64_t keyframes_at_checkpoint = 0;
    bool finished = false;
    while (!finished) {
      // Frames may stop coming (camera unplugged), so wake up regularly for checkpoints.
      if (Frame* frame = queue.pop(std::chrono::milliseconds(100), finished)) {
        stats_.queue_latency.record(now() - frame->captured_at);
        try {
          const bool keyframe = mapper.process(*frame);
          publication.afterFrame(*frame, mapper, stats_, keyframe);
        } catch (const std::exception& e) {
          error.set(std::string(frame->origin) + ": " + e.what());
          control.stop.store(true);
        }
        queue.release(frame);
        stats_.frames_processed.fetch_add(1);
      }
      const std::uint64_t keyframes = stats_.keyframes.load();
      const bool by_count = config_.checkpoint_every_keyframes > 0 &&
                            keyframes - keyframes_at_checkpoint >=
                                static_cast<std::uint64_t>(config_.checkpoint_every_keyframes);
      const bool by_time = config_.checkpoint_every_seconds > 0 &&
                           now() - last_checkpoint >= config_.checkpoint_every_seconds &&
                           keyframes > keyframes_at_checkpoint;
      if (control.snapshot.exchange(false) || by_count || by_time) {
        writer.submit(mapper.snapshot(), outputs_.map_path);
        keyframes_at_checkpoint = keyframes;
        last_checkpoint = now();
      }
    }
    // A snapshot request that came while the queue was draining is served by the final save.
    control.snapshot.store(false);
    mapping_done.store(true);
  });

  // Status until the mapping thread has drained everything.
  const bool tty = outputs_.status_line && ::isatty(STDERR_FILENO);
  double last_print = 0;
  bool stop_announced = false;
  while (!mapping_done.load()) {
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
  mapping.join();
  stats_.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  stats_.frames_dropped.store(queue.dropped());
  stats_.queue_depth.store(0);
  if (tty) std::fprintf(stderr, "\r%s\033[K\n", statusLine(stats_, stats_.wall_seconds).c_str());

  // Final save, through the writer so it is ordered after any checkpoint in flight.
  const std::shared_ptr<const MapCloud> final_map = mapper.snapshot();
  writer.submit(final_map, outputs_.map_path);
  publication.atEnd(final_map);
  const CheckpointWriter::Result final_write = writer.flush();
  int exit_code = 0;
  if (!final_write.ok) {
    spdlog::error("final map not saved: {}", final_write.error);
    exit_code = 1;
  } else {
    spdlog::info("map: {} points written to {}", final_write.points, final_write.path);
  }
  if (!outputs_.trajectory_path.empty()) {
    try {
      mapper.keyframeTrajectory().save(outputs_.trajectory_path);
    } catch (const std::exception& e) {
      spdlog::error("keyframe trajectory not saved: {}", e.what());
      exit_code = 1;
    }
  }
  stats_.peak_rss_mb = peakRssMb();
  const std::string fatal = error.get();
  if (!fatal.empty()) {
    spdlog::error("{}", fatal);
    exit_code = 1;
  }
  return exit_code;
}

}  // namespace rgbdmap
