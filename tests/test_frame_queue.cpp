#include <gtest/gtest.h>

#include <thread>

#include "rgbdmap/frame_queue.hpp"

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

TEST(FrameQueue, DropOldestNeverBlocksAndKeepsNewest) {
  FrameQueue queue(3, QueuePolicy::kDropOldest, 8, 6);
  // Nobody consumes: the producer must still get a frame every time.
  for (std::uint64_t i = 0; i < 20; ++i) {
    Frame* f = queue.acquire();
    ASSERT_NE(f, nullptr);
    f->index = i;
    queue.push(f);
  }
  EXPECT_EQ(queue.dropped(), 17u);
  EXPECT_EQ(queue.depth(), 3u);
  queue.close();
  bool finished = false;
  std::vector<std::uint64_t> got;
  while (Frame* f = queue.pop(std::chrono::milliseconds(10), finished)) {
    got.push_back(f->index);
    queue.release(f);
  }
  EXPECT_EQ(got, (std::vector<std::uint64_t>{17, 18, 19}));
}

TEST(FrameQueue, DropOldestUnderConcurrentConsumer) {
  FrameQueue queue(2, QueuePolicy::kDropOldest, 8, 6);
  constexpr std::uint64_t kFrames = 3000;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kFrames; ++i) {
      Frame* f = queue.acquire();
      ASSERT_NE(f, nullptr);
      f->index = i;
      queue.push(f);
    }
    queue.close();
  });
  std::uint64_t received = 0, last = 0;
  bool finished = false, first = true;
  while (!finished) {
    if (Frame* f = queue.pop(std::chrono::milliseconds(50), finished)) {
      if (!first) {
        EXPECT_GT(f->index, last);  // order survives drops
      }
      first = false;
      last = f->index;
      ++received;
      std::this_thread::sleep_for(std::chrono::microseconds(50));  // a slow mapper
      queue.release(f);
    }
  }
  producer.join();
  EXPECT_EQ(received + queue.dropped(), kFrames);
  EXPECT_EQ(last, kFrames - 1);  // the newest frame is never the one dropped
}

}  // namespace
}  // namespace rgbdmap
