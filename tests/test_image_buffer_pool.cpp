// The pool keyframe images come from: a buffer let go is handed out again for the next image of
// its size, on whichever thread it was let go, and no more is kept than the pool is allowed.
// (Threaded: CI runs it under ThreadSanitizer.)
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <thread>

#include "rgbdmap/base/image_buffer_pool.hpp"

namespace rgbdmap {
namespace {

TEST(ImageBufferPool, AnImageLetGoIsReusedForTheNextOfItsSize) {
  ImageBufferPool pool(16u << 20);
  cv::Mat depth = pool.image(480, 640, CV_32FC1);
  const uchar* buffer = depth.data;
  depth.setTo(1.5f);
  cv::Mat shared = depth;  // a header sharing the buffer keeps it from the pool
  depth.release();
  EXPECT_EQ(pool.keptBytes(), 0u);
  shared.release();
  EXPECT_EQ(pool.keptBytes(), 480u * 640u * 4u);

  cv::Mat again = pool.image(480, 640, CV_32FC1);
  EXPECT_EQ(again.data, buffer);
  EXPECT_EQ(pool.allocations(), 1u);
  // Another size is a buffer of its own; an OpenCV function writing into a pooled image of the
  // size and type it makes keeps the buffer.
  cv::Mat gray = pool.image(480, 640, CV_8UC1);
  const uchar* gray_buffer = gray.data;
  cv::Mat color(480, 640, CV_8UC3, cv::Scalar(10, 20, 30));
  cv::cvtColor(color, gray, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(gray.data, gray_buffer);
  EXPECT_EQ(pool.allocations(), 2u);
  EXPECT_EQ(gray.at<uchar>(100, 100),
            cv::saturate_cast<uchar>(0.299 * 30 + 0.587 * 20 + 0.114 * 10));
}

TEST(ImageBufferPool, KeepsNoMoreThanItsLimit) {
  ImageBufferPool pool(1u << 20);
  {
    cv::Mat a = pool.image(480, 640, CV_16UC1);  // 600 KB each
    cv::Mat b = pool.image(480, 640, CV_16UC1);
    a.setTo(1);
    b.setTo(2);
  }
  EXPECT_EQ(pool.keptBytes(), 480u * 640u * 2u);  // the second did not fit: freed
  EXPECT_EQ(pool.allocations(), 2u);
}

TEST(ImageBufferPool, ABufferLetGoOnAnotherThreadIsReused) {
  ImageBufferPool pool(16u << 20);
  cv::Mat depth = pool.image(480, 640, CV_32FC1);
  const uchar* buffer = depth.data;
  depth.setTo(2.0f);
  double sum = 0;
  std::thread reader([&sum, image = std::move(depth)]() mutable {
    sum = cv::sum(image)[0];
    image.release();
  });
  reader.join();
  EXPECT_DOUBLE_EQ(sum, 2.0 * 480 * 640);
  cv::Mat again = pool.image(480, 640, CV_32FC1);
  EXPECT_EQ(again.data, buffer);
  again.setTo(3.0f);  // written here after the reader's reads there
  EXPECT_EQ(pool.allocations(), 1u);
}

TEST(ImageBufferPool, ReservedBuffersServeTheFirstImages) {
  ImageBufferPool pool(16u << 20);
  pool.reserve(480, 640, CV_8UC3, 3);
  pool.reserve(480, 640, CV_8UC3, 2);  // already there
  EXPECT_EQ(pool.allocations(), 3u);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 3; ++i) images.push_back(pool.image(480, 640, CV_8UC3));
  EXPECT_EQ(pool.allocations(), 3u);
  EXPECT_EQ(pool.keptBytes(), 0u);
  images.push_back(pool.image(480, 640, CV_8UC3));
  EXPECT_EQ(pool.allocations(), 4u);
}

TEST(ImageBufferPool, ImagesOfTheProcessPoolAreCopies) {
  cv::Mat color(48, 64, CV_8UC3, cv::Scalar(1, 2, 3));
  cv::Mat copy = pooledCopy(color);
  EXPECT_NE(copy.data, color.data);
  EXPECT_EQ(copy.size(), color.size());
  EXPECT_EQ(copy.type(), color.type());
  EXPECT_EQ(cv::norm(copy, color, cv::NORM_INF), 0.0);
  EXPECT_TRUE(pooledCopy(cv::Mat()).empty());
}

}  // namespace
}  // namespace rgbdmap
