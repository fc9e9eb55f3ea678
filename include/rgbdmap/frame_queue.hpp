#pragma once

#include <atomic>
#include <chrono>
#include <boost/lockfree/queue.hpp>
#include <boost/lockfree/spsc_queue.hpp>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "rgbdmap/frame.hpp"

namespace rgbdmap {

// What the capture side does when the mapper has not taken the queued frames yet.
enum class QueuePolicy {
  kDropOldest,  // live camera: never block the sensor, discard the stalest queued frame
  kBlock,       // replay: wait, lose nothing
};

// A bounded frame queue between one capture thread and one mapping thread, with the frames
// drawn from a pool allocated up front, so steady state allocates nothing.
//
// Filled frames travel through a Boost.Lockfree queue. Dropping the oldest frame needs the
// producer to pop from the head as well, which Boost's spsc_queue forbids, so the filled-frame
// queue is Boost's bounded lock-free queue (fixed-size, no allocation after construction);
// emptied frames go back to the producer through a spsc_queue.
class FrameQueue {
 public:
  FrameQueue(std::size_t capacity, QueuePolicy policy, int width, int height);

  // Producer side. acquire() hands out an empty frame to fill; never blocks in kDropOldest.
  // Returns nullptr only after close().
  Frame* acquire();
  // Queues a filled frame. In kBlock mode waits for room (unless closed).
  void push(Frame* frame);
  // No more frames will come; the consumer drains what is queued, then pop() returns nullptr.
  void close();

  // Consumer side. Waits up to `timeout` for the next frame; nullptr on timeout or, with
  // `finished` set, when the queue is closed and drained.
  Frame* pop(std::chrono::milliseconds timeout, bool& finished);
  // Returns a frame taken with pop() to the pool.
  void release(Frame* frame);

  // Makes a blocked producer give up (used to abort without draining).
  void abort();

  std::size_t capacity() const { return capacity_; }
  std::size_t depth() const {
    const std::int64_t n = queued_.load(std::memory_order_relaxed);
    return n > 0 ? static_cast<std::size_t>(n) : 0;  // briefly -1 while a push is in flight
  }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::size_t capacity_;
  QueuePolicy policy_;
  std::vector<std::unique_ptr<Frame>> storage_;
  boost::lockfree::queue<Frame*, boost::lockfree::fixed_sized<true>> filled_;
  boost::lockfree::spsc_queue<Frame*> free_;
  Frame* spare_ = nullptr;  // a dropped frame the producer reuses directly
  std::atomic<std::int64_t> queued_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<bool> closed_{false};
  std::atomic<bool> aborted_{false};
};

}  // namespace rgbdmap
