#include "rgbdmap/runtime/capture_thread.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <exception>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/base/thread_name.hpp"

namespace rgbdmap {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

CaptureThread::CaptureThread(FrameSource& source, FrameQueue& queue, RunStats& stats,
                             RunControl& control, ErrorHandler on_error,
                             DepthRegistration* registration)
    : source_(source),
      queue_(queue),
      stats_(stats),
      control_(control),
      on_error_(std::move(on_error)),
      registration_(registration),
      thread_(control) {
  thread_.start([this] { run(); });
}

void CaptureThread::run() {
  nameThisThread("rgbdmap-capture");
  try {
    read();
  } catch (const std::exception& e) {
    if (on_error_) on_error_(e.what());
  }
  stats_.frames_skipped.store(source_.skipped());
  queue_.close();
}

void CaptureThread::read() {
  Frame* frame = nullptr;
  while (!control_.stop.load()) {
    if (!frame && !(frame = queue_.acquire())) break;
    const auto read_start = Clock::now();
    const ReadStatus status = source_.read(*frame);
    if (status == ReadStatus::kEnd) break;
    if (status == ReadStatus::kSkipped) {
      stats_.frames_skipped.store(source_.skipped());
      continue;  // keep the slot for the next read
    }
    if (status == ReadStatus::kTimeout) {
      if (!source_.canReconnect())
        throw InputError(source_.describe() + ": camera stopped delivering frames");
      waitForCamera();
      continue;
    }
    if (registration_) registration_->apply(frame->depth);
    stats_.read_latency.record(secondsSince(read_start));
    frame->index = index_++;
    frame->captured_at = steadySeconds();
    stats_.frames_captured.fetch_add(1);
    queue_.push(frame);
    frame = nullptr;
    stats_.frames_dropped.store(queue_.dropped());
  }
  // A frame still held here stays in the pool's storage; only the mapper returns frames.
}

void CaptureThread::waitForCamera() {
  // Keep everything mapped: checkpoint now, then wait for the same camera. A camera that reopens
  // but delivers nothing does not rewrite an unchanged map every cycle.
  stats_.disconnects.fetch_add(1);
  const bool new_frames = index_ != index_at_outage_checkpoint_;
  if (new_frames) control_.snapshot.store(true);
  index_at_outage_checkpoint_ = index_;
  spdlog::warn(
      "{}: camera stopped delivering frames; {}, waiting for it to come back (Ctrl-C saves and "
      "quits)",
      source_.describe(),
      new_frames ? "map checkpointed" : "no new frame since the last checkpoint");
  while (!control_.stop.load() && !source_.reconnect()) {
  }
  if (!control_.stop.load())
    spdlog::info("{}: camera is back, mapping resumes", source_.describe());
}

}  // namespace rgbdmap
