#include "rgbdmap/tracking/orb_matches.hpp"

#include <cstdint>
#include <cstring>
#include <limits>

#include "rgbdmap/base/vector_clones.hpp"

namespace rgbdmap {
namespace {

struct NearestTwo {
  int row = -1;  // of the nearest train descriptor
  int distance = std::numeric_limits<int>::max();
  int second = std::numeric_limits<int>::max();  // distance of the second nearest
};

// Descriptors of `words` 64-bit words, a multiple of 4 (ORB's 32 bytes are 4), taken four at a
// time: four independent popcounts per step instead of a chain of one. Reads and writes only the
// caller's private buffers, so ThreadSanitizer is not made to check each of a comparison's
// hundreds of thousands of pairs (OpenCV's matcher, which this replaces, was never instrumented).
RGBDMAP_VECTOR_CLONES __attribute__((no_sanitize("thread"))) void nearestTwo(
    const std::uint64_t* query, std::size_t query_rows, const std::uint64_t* train,
    std::size_t train_rows, std::size_t words, NearestTwo* nearest) {
  for (std::size_t i = 0; i < query_rows; ++i) {
    const std::uint64_t* q = query + i * words;
    NearestTwo n;
    for (std::size_t j = 0; j < train_rows; ++j) {
      const std::uint64_t* t = train + j * words;
      int d = 0;
      for (std::size_t w = 0; w < words; w += 4)
        d += __builtin_popcountll(q[w] ^ t[w]) + __builtin_popcountll(q[w + 1] ^ t[w + 1]) +
             __builtin_popcountll(q[w + 2] ^ t[w + 2]) + __builtin_popcountll(q[w + 3] ^ t[w + 3]);
      if (d < n.distance) {
        n.second = n.distance;
        n.distance = d;
        n.row = static_cast<int>(j);
      } else if (d < n.second) {
        n.second = d;
      }
    }
    nearest[i] = n;
  }
}

// The rows of a descriptor matrix as whole 64-bit words, zero-padded (padding adds no distance).
void packRows(const cv::Mat& descriptors, std::size_t words, std::vector<std::uint64_t>& out) {
  out.assign(static_cast<std::size_t>(descriptors.rows) * words, 0);
  const std::size_t bytes = static_cast<std::size_t>(descriptors.cols);
  for (int r = 0; r < descriptors.rows; ++r)
    std::memcpy(out.data() + static_cast<std::size_t>(r) * words, descriptors.ptr(r), bytes);
}

}  // namespace

void ratioMatches(const cv::Mat& query, const cv::Mat& train, std::vector<cv::DMatch>& matches,
                  float ratio) {
  matches.clear();
  if (query.rows < 2 || train.rows < 2) return;
  CV_Assert(query.type() == CV_8UC1 && train.type() == CV_8UC1 && query.cols == train.cols);
  const std::size_t words = (static_cast<std::size_t>(query.cols) + 31) / 32 * 4;
  // Kept between calls: a keyframe is compared with tens of places.
  thread_local std::vector<std::uint64_t> packed_query, packed_train;
  thread_local std::vector<NearestTwo> nearest;
  packRows(query, words, packed_query);
  packRows(train, words, packed_train);
  nearest.resize(static_cast<std::size_t>(query.rows));
  nearestTwo(packed_query.data(), static_cast<std::size_t>(query.rows), packed_train.data(),
             static_cast<std::size_t>(train.rows), words, nearest.data());
  for (std::size_t i = 0; i < nearest.size(); ++i) {
    const NearestTwo& n = nearest[i];
    if (n.row >= 0 && static_cast<float>(n.distance) <= ratio * static_cast<float>(n.second))
      matches.emplace_back(static_cast<int>(i), n.row, static_cast<float>(n.distance));
  }
}

}  // namespace rgbdmap
