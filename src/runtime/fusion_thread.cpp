#include "rgbdmap/runtime/fusion_thread.hpp"

#include <chrono>
#include <exception>

#include "rgbdmap/base/thread_name.hpp"
#include "rgbdmap/base/thread_priority.hpp"

namespace rgbdmap {
FusionThread::FusionThread(Mapper& mapper, std::size_t slots, int width, int height,
                           ErrorHandler on_error)
    : mapper_(mapper),
      keyframes_(slots, QueuePolicy::kBlock, width, height),
      on_error_(std::move(on_error)),
      thread_([this] { run(); }) {}

FusionThread::~FusionThread() { finish(); }

bool FusionThread::submit(const Frame& keyframe, bool wait, Settled at) {
  Frame* slot = wait ? keyframes_.acquire() : keyframes_.tryAcquire();
  if (!slot) return false;
  copyFrame(keyframe, *slot);
  if (at) {
    follows_while_idle_.store(false);
    std::lock_guard<std::mutex> lock(pinned_mutex_);
    pinned_[slot] = std::move(at);
  }
  keyframes_.push(slot);
  return true;
}

void FusionThread::request(MapRequest kind, MapTask task) {
  {
    std::lock_guard<std::mutex> lock(request_mutex_);
    pending_[static_cast<std::size_t>(kind)] = std::move(task);
  }
  requested_.store(true);
}

void FusionThread::finish() {
  keyframes_.close();
  if (thread_.joinable()) thread_.join();
}

void FusionThread::serveRequest() {
  std::array<MapTask, 2> tasks;
  {
    std::lock_guard<std::mutex> lock(request_mutex_);
    std::swap(tasks, pending_);
  }
  for (const MapTask& task : tasks)
    if (task) task(mapper_);
}

void FusionThread::run() {
  nameThisThread("rgbdmap-fusion");
  // The map may lag a few keyframes behind (they wait in the queue); a frame's pose may not.
  stepBackFromTracking(kFusionNiceness);
  bool finished = false;
  bool failed = false;
  while (!finished) {
    // Short waits: a checkpoint request is served within this even when no keyframe comes.
    Frame* keyframe = keyframes_.pop(std::chrono::milliseconds(20), finished);
    if (keyframe) {
      // After a failure the remaining keyframes are drained unfused: the map stays as it was.
      if (!failed) {
        Settled settled;
        {
          std::lock_guard<std::mutex> lock(pinned_mutex_);
          if (auto it = pinned_.find(keyframe); it != pinned_.end()) {
            settled = std::move(it->second);
            pinned_.erase(it);
          }
        }
        try {
          std::optional<PoseCorrections::Snapshot> at;
          if (settled) at = settled();  // may wait for the loop thread, holding no lock
          mapper_.fuse(*keyframe, at ? &*at : nullptr);
        } catch (const std::exception& e) {
          failed = true;
          if (on_error_) on_error_(keyframe->origin + ": " + e.what());
        }
      }
      keyframes_.release(keyframe);
    } else if (!finished && !failed && follows_while_idle_.load()) {
      // Idle: the map follows the latest loop closure, a kept keyframe at a time.
      try {
        mapper_.refine(1);
      } catch (const std::exception& e) {
        failed = true;
        if (on_error_) on_error_(std::string("re-fusing the map: ") + e.what());
      }
    }
    if (!finished && requested_.exchange(false)) {
      try {
        serveRequest();
      } catch (const std::exception& e) {
        if (on_error_) on_error_(std::string("checkpoint: ") + e.what());
      }
    }
  }
}

}  // namespace rgbdmap
