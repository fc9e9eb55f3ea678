#include "rgbdmap/runtime/frame_queue.hpp"

#include <thread>

namespace rgbdmap {
namespace {

// The queues are lock-free and have no wait primitive; a short sleep keeps an idle side from
// burning a core while adding at most this much latency (frames are ~33 ms apart).
void backoff() { std::this_thread::sleep_for(std::chrono::microseconds(200)); }

// Frames in the pool beyond the queue's capacity: one being filled, one being mapped, and for a
// live camera room for the frames that arrive while the mapper works on one (a slow keyframe
// or a checkpoint snapshot) before it trims the queue.
std::size_t poolSize(std::size_t capacity, QueuePolicy policy) {
  return capacity + (policy == QueuePolicy::kBlock ? 2 : 10);
}

}  // namespace

FrameQueue::FrameQueue(std::size_t capacity, QueuePolicy policy, int width, int height)
    : capacity_(capacity),
      policy_(policy),
      filled_(poolSize(capacity, policy)),
      free_(poolSize(capacity, policy) + 1) {
  const std::size_t pool =
      poolSize(capacity, policy) + (policy == QueuePolicy::kDropOldest ? 1 : 0);
  for (std::size_t i = 0; i < pool; ++i) {
    auto frame = std::make_unique<Frame>();
    frame->depth.create(height, width, CV_32FC1);
    frame->color.create(height, width, CV_8UC3);
    frame->origin.reserve(256);
    storage_.push_back(std::move(frame));
  }
  const std::size_t shared = storage_.size() - (policy == QueuePolicy::kDropOldest ? 1 : 0);
  for (std::size_t i = shared; i-- > 0;) free_.bounded_push(storage_[i].get());
  if (policy == QueuePolicy::kDropOldest) overflow_ = storage_.back().get();
}

Frame* FrameQueue::acquire() {
  Frame* frame = nullptr;
  while (!free_.pop(frame)) {
    if (closed_.load()) return nullptr;
    if (policy_ == QueuePolicy::kDropOldest) return overflow_;
    backoff();
  }
  return frame;
}

Frame* FrameQueue::tryAcquire() {
  Frame* frame = nullptr;
  return !closed_.load() && free_.pop(frame) ? frame : nullptr;
}

void FrameQueue::push(Frame* frame) {
  if (frame == overflow_) {
    dropped_.fetch_add(1);  // the whole pool is queued: this newest capture cannot be kept
    return;
  }
  // The filled queue holds the whole pool, so there is always room; in kBlock mode the
  // producer waited in acquire() instead.
  queued_.fetch_add(1);
  filled_.push(frame);
}

void FrameQueue::close() { closed_.store(true); }

Frame* FrameQueue::pop(std::chrono::milliseconds timeout, bool& finished) {
  finished = false;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  Frame* frame = nullptr;
  for (;;) {
    if (policy_ == QueuePolicy::kDropOldest) {
      // Keep only the newest `capacity_` frames: the older ones are stale for a live camera.
      while (filled_.read_available() > capacity_ && filled_.pop(frame)) {
        queued_.fetch_sub(1);
        dropped_.fetch_add(1);
        free_.bounded_push(frame);
      }
    }
    // Read `closed_` before popping: a frame pushed before close() is then always seen.
    const bool closed = closed_.load();
    if (filled_.pop(frame)) break;
    if (closed) {
      finished = true;
      return nullptr;
    }
    if (std::chrono::steady_clock::now() >= deadline) return nullptr;
    backoff();
  }
  queued_.fetch_sub(1);
  return frame;
}

void FrameQueue::release(Frame* frame) { free_.bounded_push(frame); }

void FrameQueue::freeImages() {
  for (const std::unique_ptr<Frame>& frame : storage_) {
    frame->depth.release();
    frame->color.release();
  }
}

}  // namespace rgbdmap
