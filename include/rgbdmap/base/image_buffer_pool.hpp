#pragma once

#include <cstddef>
#include <map>
#include <mutex>
#include <opencv2/core.hpp>

namespace rgbdmap {

// Image buffers kept once let go and handed out again for the next image of the same size,
// instead of going back to the system. A camera-sized buffer is above glibc's mmap threshold
// (base/run_stats.cpp), so without the pool every copy maps fresh memory, faulted in page by page
// on first touch: on our machines copying one 640 x 480 colour + depth keyframe cost 6 ms that
// way, most of the tracking thread's time on a keyframe (docs/benchmarks.md).
// Thread-safe: a buffer may be let go on another thread than the one that took it.
class ImageBufferPool final : public cv::MatAllocator {
 public:
  // Keeps at most `max_kept_bytes` of buffers let go; beyond that they are freed.
  explicit ImageBufferPool(std::size_t max_kept_bytes) : max_kept_bytes_(max_kept_bytes) {}
  ~ImageBufferPool() override;

  cv::UMatData* allocate(int dims, const int* sizes, int type, void* data, std::size_t* step,
                         cv::AccessFlag flags, cv::UMatUsageFlags usage) const override;
  bool allocate(cv::UMatData* data, cv::AccessFlag flags, cv::UMatUsageFlags usage) const override;
  void deallocate(cv::UMatData* data) const override;

  // An uninitialised `rows` x `cols` image of `type` whose buffer comes from this pool. OpenCV
  // functions writing into it keep its buffer when size and type match; copies of the Mat header
  // share it, and the last one let go returns it to the pool.
  cv::Mat image(int rows, int cols, int type);

  // Makes sure `count` buffers for `rows` x `cols` images of `type` are kept, allocating and
  // touching the missing ones now: a user that knows how many images it will hold at once pays
  // for their memory before the first frame, not on it.
  void reserve(int rows, int cols, int type, int count);
  std::size_t keptBytes() const;
  // Buffers taken from the system so far (by images and reserve()).
  std::size_t allocations() const;

 private:
  const std::size_t max_kept_bytes_;
  mutable std::mutex mutex_;
  mutable std::multimap<std::size_t, void*> kept_;  // by size
  mutable std::size_t kept_bytes_ = 0;
  mutable std::size_t allocations_ = 0;
};

// The process's pool (32 MB kept at most). Never destroyed: an image may outlive any owner.
ImageBufferPool& imageBufferPool();

// imageBufferPool().image(): for images made again and again (keyframes' copies).
cv::Mat pooledImage(int rows, int cols, int type);
// A deep copy of `image` in a pooled buffer.
cv::Mat pooledCopy(const cv::Mat& image);

}  // namespace rgbdmap
