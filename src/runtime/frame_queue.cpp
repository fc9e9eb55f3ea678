#include "rgbdmap/runtime/frame_queue.hpp"

namespace rgbdmap {
namespace {

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
  if (free_.pop(frame)) return frame;
  if (policy_ == QueuePolicy::kDropOldest) return closed_.load() ? nullptr : overflow_;
  std::unique_lock<std::mutex> lock(wait_mutex_);
  changed_.wait(lock, [&] { return free_.pop(frame) || closed_.load(); });
  return frame;  // nullptr: closed
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
  wake();
}

void FrameQueue::close() {
  closed_.store(true);
  wake();
}

Frame* FrameQueue::pop(std::chrono::milliseconds timeout, bool& finished) {
  Frame* frame = nullptr;
  const auto take = [&] {
    if (policy_ == QueuePolicy::kDropOldest) {
      // Keep only the newest `capacity_` frames: the older ones are stale for a live camera.
      Frame* stale = nullptr;
      while (filled_.read_available() > capacity_ && filled_.pop(stale)) {
        queued_.fetch_sub(1);
        dropped_.fetch_add(1);
        free_.bounded_push(stale);
      }
    }
    // Read `closed_` before popping: a frame pushed before close() is then always seen.
    const bool closed = closed_.load();
    return filled_.pop(frame) || closed;
  };
  finished = false;
  if (!take()) {
    std::unique_lock<std::mutex> lock(wait_mutex_);
    if (!changed_.wait_until(lock, std::chrono::steady_clock::now() + timeout, take))
      return nullptr;
  }
  finished = frame == nullptr;  // closed and drained
  if (finished) return nullptr;
  queued_.fetch_sub(1);
  return frame;
}

void FrameQueue::release(Frame* frame) {
  free_.bounded_push(frame);
  wake();
}

void FrameQueue::wake() {
  // Taking the lock orders this change after a waiter's look at the queues: it either saw the
  // change or is already waiting when notified.
  { std::lock_guard<std::mutex> lock(wait_mutex_); }
  changed_.notify_all();
}

void FrameQueue::freeImages() {
  for (const std::unique_ptr<Frame>& frame : storage_) {
    frame->depth.release();
    frame->color.release();
  }
}

}  // namespace rgbdmap
