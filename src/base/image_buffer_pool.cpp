#include "rgbdmap/base/image_buffer_pool.hpp"

#include <cstring>

namespace rgbdmap {

ImageBufferPool::~ImageBufferPool() {
  for (auto& [size, buffer] : kept_) cv::fastFree(buffer);
}

cv::UMatData* ImageBufferPool::allocate(int dims, const int* sizes, int type, void* data,
                                        std::size_t* step, cv::AccessFlag,
                                        cv::UMatUsageFlags) const {
  // The layout OpenCV's own allocator gives: rows packed, or the caller's steps for its data.
  std::size_t total = CV_ELEM_SIZE(type);
  for (int i = dims - 1; i >= 0; --i) {
    if (step) {
      if (data && step[i] != cv::Mat::AUTO_STEP)
        total = step[i];
      else
        step[i] = total;
    }
    total *= static_cast<std::size_t>(sizes[i]);
  }
  auto* u = new cv::UMatData(this);
  if (data) {
    u->flags |= cv::UMatData::USER_ALLOCATED;
  } else {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto kept = kept_.find(total);
    if (kept != kept_.end()) {
      data = kept->second;
      kept_bytes_ -= total;
      kept_.erase(kept);
    } else {
      ++allocations_;
    }
  }
  if (!data) data = cv::fastMalloc(total);
  u->data = u->origdata = static_cast<uchar*>(data);
  u->size = total;
  return u;
}

bool ImageBufferPool::allocate(cv::UMatData* data, cv::AccessFlag, cv::UMatUsageFlags) const {
  return data != nullptr;
}

void ImageBufferPool::deallocate(cv::UMatData* u) const {
  if (!u) return;
  CV_Assert(u->urefcount == 0 && u->refcount == 0);
  if (!(u->flags & cv::UMatData::USER_ALLOCATED) && u->origdata) {
    bool kept = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (kept_bytes_ + u->size <= max_kept_bytes_) {
        kept_.emplace(u->size, u->origdata);
        kept_bytes_ += u->size;
        kept = true;
      }
    }
    if (!kept) cv::fastFree(u->origdata);
  }
  delete u;
}

cv::Mat ImageBufferPool::image(int rows, int cols, int type) {
  cv::Mat out;
  out.allocator = this;
  out.create(rows, cols, type);
  return out;
}

void ImageBufferPool::reserve(int rows, int cols, int type, int count) {
  const std::size_t bytes = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) *
                            static_cast<std::size_t>(CV_ELEM_SIZE(type));
  if (bytes == 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto n = static_cast<std::ptrdiff_t>(kept_.count(bytes)); n < count; ++n) {
    if (kept_bytes_ + bytes > max_kept_bytes_) return;
    void* buffer = cv::fastMalloc(bytes);
    ++allocations_;
    std::memset(buffer, 0, bytes);  // the pages are touched here, not on the first image
    kept_.emplace(bytes, buffer);
    kept_bytes_ += bytes;
  }
}

std::size_t ImageBufferPool::allocations() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return allocations_;
}

std::size_t ImageBufferPool::keptBytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return kept_bytes_;
}

ImageBufferPool& imageBufferPool() {
  static ImageBufferPool* pool = new ImageBufferPool(32u << 20);
  return *pool;
}

cv::Mat pooledImage(int rows, int cols, int type) {
  return imageBufferPool().image(rows, cols, type);
}

cv::Mat pooledCopy(const cv::Mat& image) {
  cv::Mat copy = pooledImage(image.rows, image.cols, image.type());
  image.copyTo(copy);
  return copy;
}

}  // namespace rgbdmap
