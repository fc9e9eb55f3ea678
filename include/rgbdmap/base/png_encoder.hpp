#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

struct libdeflate_compressor;

namespace rgbdmap {

// Writes PNGs without OpenCV's image codecs (whose library brings GDAL, poppler and some 130
// other libraries, about 40 MB of memory in every process that links it): 8-bit grey, BGR and
// BGRA images and 16-bit grey and BGR ones, as any PNG reader expects them (RGB order, big-endian
// samples). Each row gets the filter that leaves the smallest sum of absolute differences (the
// heuristic libpng uses) and libdeflate compresses the whole image in one call.
//
// Holds its buffers and its compressor between calls; not thread-safe.
class PngEncoder {
 public:
  // level: 0 (stored) to 9 (smallest), as IMWRITE_PNG_COMPRESSION.
  explicit PngEncoder(int level = 1);
  ~PngEncoder();
  PngEncoder(PngEncoder&&) noexcept;
  PngEncoder& operator=(PngEncoder&&) noexcept;

  static bool supports(const cv::Mat& image);
  // The PNG file's bytes; false (with `error`) for an image type supports() refuses.
  bool encode(const cv::Mat& image, std::vector<std::uint8_t>& png, std::string& error);

 private:
  struct FreeCompressor {
    void operator()(libdeflate_compressor* c) const;
  };
  std::unique_ptr<libdeflate_compressor, FreeCompressor> deflater_;
  std::vector<std::uint8_t> raw_;        // the image's rows as PNG samples
  std::vector<std::uint8_t> filtered_;   // each row: its filter byte and the filtered row
  std::vector<std::uint8_t> candidate_;  // one row under each filter while choosing
};

}  // namespace rgbdmap
