#include "rgbdmap/frame_queue.hpp"

#include <chrono>
#include <thread>

namespace rgbdmap {
namespace {

// The queues are lock-free and have no wait primitive; a short sleep keeps an idle side from
// burning a core while adding at most this much latency (a frame is ~33 ms apart).
void backoff() { std::this_thread::sleep_for(std::chrono::microseconds(200)); }

}  // namespace

FrameQueue::FrameQueue(std::size_t capacity, QueuePolicy policy, int width, int height)
    : capacity_(capacity), policy_(policy), filled_(capacity), free_(capacity + 2) {
  // capacity queued + one being filled + one being mapped: the producer never runs dry.
  for (std::size_t i = 0; i < capacity + 2; ++i) {
    auto frame = std::make_unique<Frame>();
    frame->depth.create(height, width, CV_32FC1);
    frame->color.create(height, width, CV_8UC3);
    frame->origin.reserve(256);
    free_.push(frame.get());
    storage_.push_back(std::move(frame));
  }
}

Frame* FrameQueue::acquire() {
  if (spare_) return std::exchange(spare_, nullptr);
  Frame* frame = nullptr;
  while (!free_.pop(frame)) {
    if (closed_.load() || aborted_.load()) return nullptr;
    backoff();
  }
  return frame;
}

void FrameQueue::push(Frame* frame) {
  while (!filled_.bounded_push(frame)) {
    if (aborted_.load()) {
      spare_ = frame;
      return;
    }
    if (policy_ == QueuePolicy::kDropOldest) {
      Frame* oldest = nullptr;
      if (filled_.pop(oldest)) {
        queued_.fetch_sub(1);
        dropped_.fetch_add(1);
        if (spare_) free_.push(spare_);  // cannot happen with one producer, but never leak
        spare_ = oldest;
      }
    } else {
      backoff();
    }
  }
  queued_.fetch_add(1);
}

void FrameQueue::close() { closed_.store(true); }

void FrameQueue::abort() {
  aborted_.store(true);
  closed_.store(true);
}

Frame* FrameQueue::pop(std::chrono::milliseconds timeout, bool& finished) {
  finished = false;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  Frame* frame = nullptr;
  while (!filled_.pop(frame)) {
    if (closed_.load()) {
      // The producer may have pushed just before closing: look once more.
      if (filled_.pop(frame)) break;
      finished = true;
      return nullptr;
    }
    if (std::chrono::steady_clock::now() >= deadline) return nullptr;
    backoff();
  }
  queued_.fetch_sub(1);
  return frame;
}

void FrameQueue::release(Frame* frame) { free_.push(frame); }

}  // namespace rgbdmap
