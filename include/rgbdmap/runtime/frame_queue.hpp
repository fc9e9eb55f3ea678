#pragma once

#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <boost/lockfree/stack.hpp>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "rgbdmap/base/frame.hpp"

namespace rgbdmap {

// What the capture side does when the mapper has not taken the queued frames yet.
enum class QueuePolicy {
  kDropOldest,  // live camera: never block the sensor, discard the stalest queued frame
  kBlock,       // replay: wait, lose nothing
};

// A bounded frame queue between one capture thread and one mapping thread, with the frames
// drawn from a pool allocated up front, so steady state allocates nothing. Both directions are
// Boost.Lockfree: an spsc_queue of filled frames to the mapper, and a stack of emptied frames
// back. A side that finds nothing to take waits on a condition variable the other side signals
// (it polled every 200 us before: a lossless replay of a floor spent 3 % more CPU). The frame
// given back last is taken next, so while the mapper keeps up only the two or three frames in
// flight are ever written to: the rest of the pool is never touched and takes no resident memory (a
// queue of spare frames cycled through all 19 of a live camera's, 40 MB).
//
// kDropOldest keeps the camera from ever waiting: the filled queue can physically hold every
// frame of the pool, and the consumer, when it pops, discards all but the newest `capacity`
// queued frames (the oldest ones) and counts them. Only if the mapper stalls so long that the
// whole pool is queued does the producer capture into a private overflow frame, which is then
// dropped (counted) instead of queued.
class FrameQueue {
 public:
  FrameQueue(std::size_t capacity, QueuePolicy policy, int width, int height);

  // Producer side. acquire() hands out an empty frame to fill; never blocks in kDropOldest.
  // Returns nullptr only after close().
  Frame* acquire();
  // Like acquire(), but nullptr at once when no frame of the pool is free (never the overflow
  // frame).
  Frame* tryAcquire();
  // Queues a frame from acquire(). Never blocks.
  void push(Frame* frame);
  // No more frames will come; the consumer drains what is queued, then pop() finishes.
  void close();

  // Consumer side. Waits up to `timeout` for the next frame; nullptr on timeout or, with
  // `finished` set, when the queue is closed and drained.
  Frame* pop(std::chrono::milliseconds timeout, bool& finished);
  // Returns a frame taken with pop() to the pool.
  void release(Frame* frame);

  // Frees the pool's images, once neither side uses the queue any more (both threads joined): the
  // final save needs the memory more.
  void freeImages();

  std::size_t capacity() const { return capacity_; }
  std::size_t depth() const {
    const std::int64_t n = queued_.load(std::memory_order_relaxed);
    return n > 0 ? static_cast<std::size_t>(n) : 0;  // briefly -1 while a push is in flight
  }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  void wake();  // after a change the other side may wait for: a push, a release, close()

  std::size_t capacity_;
  QueuePolicy policy_;
  std::vector<std::unique_ptr<Frame>> storage_;
  boost::lockfree::spsc_queue<Frame*> filled_;
  boost::lockfree::stack<Frame*> free_;  // bounded_push only: never allocates
  Frame* overflow_ = nullptr;            // kDropOldest: captured into when the pool is exhausted
  std::atomic<std::int64_t> queued_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<bool> closed_{false};
  std::mutex wait_mutex_;  // guards no data: orders a waiter's look at the queues and a wake()
  std::condition_variable changed_;
};

}  // namespace rgbdmap
