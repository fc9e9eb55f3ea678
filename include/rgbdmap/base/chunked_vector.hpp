#pragma once

#include <algorithm>
#include <cstddef>
#include <memory>
#include <vector>

namespace rgbdmap {

// A growing array of T kept in chunks of kChunk elements, each allocated whole: growing never
// moves an element (references stay valid), and a chunk large enough (the C library's mmap
// threshold, 512 KB: tuneAllocator()) is mapped on its own and handed back to the system the
// moment it is freed. Small nodes, as a deque's, scatter over the heap instead: a map freed and
// fused again (a re-fusion pass) left holes that other allocations took, and a long run's heap
// crept up with every pass.
template <typename T, std::size_t kChunk>
class ChunkedVector {
 public:
  ChunkedVector() = default;
  ChunkedVector(const ChunkedVector& other) : size_(other.size_) {
    for (const auto& chunk : other.chunks_) {
      chunks_.push_back(std::make_unique<T[]>(kChunk));
      std::copy(chunk.get(), chunk.get() + kChunk, chunks_.back().get());
    }
  }
  ChunkedVector& operator=(const ChunkedVector& other) {
    if (this != &other) *this = ChunkedVector(other);
    return *this;
  }
  ChunkedVector(ChunkedVector&&) noexcept = default;
  ChunkedVector& operator=(ChunkedVector&&) noexcept = default;

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  // Elements allocated (the last chunk whole).
  std::size_t capacity() const { return chunks_.size() * kChunk; }

  T& operator[](std::size_t i) { return chunks_[i / kChunk][i % kChunk]; }
  const T& operator[](std::size_t i) const { return chunks_[i / kChunk][i % kChunk]; }

  // Empty, its chunks kept for the elements added next: a map fused again from scratch reuses
  // the memory it had instead of handing it back and faulting it in again.
  void clear() { size_ = 0; }
  // Hands back the chunks no element is in.
  void releaseUnused() { chunks_.resize(std::min(chunks_.size(), (size_ + kChunk - 1) / kChunk)); }

  // A default-constructed element at the end.
  T& emplace_back() {
    if (size_ == capacity()) chunks_.push_back(std::make_unique<T[]>(kChunk));
    T& added = (*this)[size_++];
    added = T{};
    return added;
  }

 private:
  std::vector<std::unique_ptr<T[]>> chunks_;
  std::size_t size_ = 0;
};

}  // namespace rgbdmap
