#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "rgbdmap/runtime/frame_queue.hpp"

namespace rgbdmap {
namespace {

TEST(FrameQueue, BlockingModeIsLosslessAndOrdered) {
  FrameQueue queue(4, QueuePolicy::kBlock, 8, 6);
  constexpr std::uint64_t kFrames = 2000;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kFrames; ++i) {
      Frame* f = queue.acquire();
      ASSERT_NE(f, nullptr);
      f->index = i;
      f->depth.setTo(static_cast<float>(i));
      queue.push(f);
    }
    queue.close();
  });
  std::uint64_t expected = 0;
  bool finished = false;
  while (!finished) {
    if (Frame* f = queue.pop(std::chrono::milliseconds(50), finished)) {
      EXPECT_EQ(f->index, expected);
      EXPECT_EQ(f->depth.at<float>(0, 0), static_cast<float>(expected));
      ++expected;
      if (expected % 100 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      queue.release(f);
    }
  }
  producer.join();
  EXPECT_EQ(expected, kFrames);
  EXPECT_EQ(queue.dropped(), 0u);
}

TEST(FrameQueue, TryAcquireNeverWaits) {
  // capacity 1 in blocking mode: a pool of 3 frames.
  FrameQueue queue(1, QueuePolicy::kBlock, 8, 6);
  std::vector<Frame*> taken;
  for (int i = 0; i < 3; ++i) {
    taken.push_back(queue.tryAcquire());
    ASSERT_NE(taken.back(), nullptr) << i;
  }
  EXPECT_EQ(queue.tryAcquire(), nullptr);  // all in use: at once, no wait
  queue.release(taken.back());
  EXPECT_EQ(queue.tryAcquire(), taken.back());
  queue.release(taken.front());
  queue.close();
  EXPECT_EQ(queue.tryAcquire(), nullptr);  // closed
}

TEST(FrameQueue, DropOldestKeepsTheNewestQueuedFrames) {
  FrameQueue queue(3, QueuePolicy::kDropOldest, 8, 6);
  for (std::uint64_t i = 0; i < 8; ++i) {
    Frame* f = queue.acquire();
    ASSERT_NE(f, nullptr);
    f->index = i;
    queue.push(f);
  }
  queue.close();
  bool finished = false;
  std::vector<std::uint64_t> got;
  while (Frame* f = queue.pop(std::chrono::milliseconds(10), finished)) {
    got.push_back(f->index);
    queue.release(f);
  }
  EXPECT_TRUE(finished);
  EXPECT_EQ(got, (std::vector<std::uint64_t>{5, 6, 7}));  // the 5 oldest were dropped
  EXPECT_EQ(queue.dropped(), 5u);
}

TEST(FrameQueue, DropOldestNeverBlocksTheCameraEvenWhenTheMapperStalls) {
  FrameQueue queue(3, QueuePolicy::kDropOldest, 8, 6);
  // Nobody consumes at all: every acquire must still return at once.
  for (std::uint64_t i = 0; i < 100; ++i) {
    Frame* f = queue.acquire();
    ASSERT_NE(f, nullptr);
    f->index = i;
    queue.push(f);
  }
  queue.close();
  bool finished = false;
  std::uint64_t received = 0;
  while (Frame* f = queue.pop(std::chrono::milliseconds(10), finished)) {
    ++received;
    queue.release(f);
  }
  EXPECT_EQ(received, 3u);
  EXPECT_EQ(received + queue.dropped(), 100u);
}

TEST(FrameQueue, DropOldestUnderConcurrentSlowConsumer) {
  FrameQueue queue(2, QueuePolicy::kDropOldest, 8, 6);
  constexpr std::uint64_t kFrames = 600;
  std::atomic<std::uint64_t> pushed{0};
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kFrames; ++i) {
      // The last frame waits for a frame of the pool to be free, as the next capture of a camera
      // that goes on would: a mapper stalled until the whole pool is queued drops the captures
      // in between (into the overflow frame), and on a loaded machine that stall can last to the
      // end (a clean run of .ci/run here: the consumer's last frame was 342 of 600).
      Frame* f = i + 1 < kFrames ? queue.acquire() : nullptr;
      while (!f && !(f = queue.tryAcquire())) std::this_thread::yield();
      ASSERT_NE(f, nullptr);
      f->index = i;
      queue.push(f);
      pushed.fetch_add(1);
      std::this_thread::sleep_for(std::chrono::microseconds(100));  // a fast camera
    }
    queue.close();
  });
  std::uint64_t received = 0, last = 0;
  bool finished = false, first = true;
  // The mapper starts late (a first keyframe's fusion): drops happen whatever the machine's
  // speed, which the sleeps below alone do not ensure on a loaded one.
  while (pushed.load() < 10) std::this_thread::yield();
  while (!finished) {
    if (Frame* f = queue.pop(std::chrono::milliseconds(50), finished)) {
      if (!first) {
        EXPECT_GT(f->index, last);  // order survives drops
      }
      first = false;
      last = f->index;
      ++received;
      std::this_thread::sleep_for(std::chrono::microseconds(500));  // a slower mapper
      queue.release(f);
    }
  }
  producer.join();
  EXPECT_EQ(received + queue.dropped(), kFrames);
  EXPECT_GT(queue.dropped(), 0u);
  EXPECT_EQ(last, kFrames - 1);  // the newest frame is kept
}

}  // namespace
}  // namespace rgbdmap
