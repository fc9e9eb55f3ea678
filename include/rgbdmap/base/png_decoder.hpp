#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

struct libdeflate_decompressor;

namespace rgbdmap {

// Decodes the PNGs that RGB-D recordings are made of (non-interlaced 8-bit RGB, RGBA or grey
// colour; 16-bit grey depth) to exactly what cv::imdecode gives, in about half its time:
// libdeflate inflates the whole image in one call and the unfiltering writes the output pixels
// as it goes. Every other PNG is left to cv::imdecode (kUnsupported), so a caller that falls
// back gets OpenCV's result for every file either way.
//
// Holds its buffers and its inflater between calls: decoding frame after frame of one size
// allocates nothing. Not thread-safe; one decoder per thread.
class PngDecoder {
 public:
  // What the caller asks for, named by the cv::imdecode flags whose result it reproduces.
  enum class Mode {
    kColor,  // cv::IMREAD_COLOR: CV_8UC3, BGR; alpha dropped, grey repeated in all three
    kDepth,  // cv::IMREAD_UNCHANGED of a 16-bit grey PNG: CV_16UC1 in host byte order
  };
  enum class Status {
    kDecoded,      // `out` holds the image
    kUnsupported,  // a PNG (perhaps valid) this decoder leaves to cv::imdecode
    kCorrupt,      // not a valid PNG: `error` says why; `out` is untouched
  };

  PngDecoder();
  ~PngDecoder();
  PngDecoder(PngDecoder&&) noexcept;
  PngDecoder& operator=(PngDecoder&&) noexcept;

  // Decodes `size` bytes of a PNG file into `out`, reusing its buffer when it already has the
  // image's size and type. Never reads outside [data, data + size).
  Status decode(const std::uint8_t* data, std::size_t size, Mode mode, cv::Mat& out,
                std::string& error);

 private:
  struct FreeDecompressor {
    void operator()(libdeflate_decompressor* d) const;
  };
  std::unique_ptr<libdeflate_decompressor, FreeDecompressor> inflater_;
  std::vector<std::uint8_t> compressed_;  // the IDAT payloads, concatenated
  std::vector<std::uint8_t> scanlines_;   // inflated: each row is a filter byte and the row
  std::vector<std::uint8_t> zero_row_;    // the row "above" the first one
};

}  // namespace rgbdmap
