// PNG files as TumSequence reads them: any bytes give an image, an error or "not mine" (left to
// OpenCV), never a crash, an out-of-bounds read or another exception. The first input byte picks
// the mode and whether the chunk CRCs are made right before decoding, so that mutations also get
// past the CRC checks to the inflater and the unfiltering.
#include <libdeflate.h>

#include <cstdint>
#include <vector>

#include "rgbdmap/base/png_decoder.hpp"

namespace {

void fixCrcs(std::vector<std::uint8_t>& png) {
  for (std::size_t pos = 8; pos + 12 <= png.size();) {
    const std::size_t length = std::size_t{png[pos]} << 24 | std::size_t{png[pos + 1]} << 16 |
                               std::size_t{png[pos + 2]} << 8 | png[pos + 3];
    if (length > png.size() - pos - 12) return;
    const std::uint32_t crc = libdeflate_crc32(0, png.data() + pos + 4, length + 4);
    for (int i = 0; i < 4; ++i)
      png[pos + 8 + length + i] = static_cast<std::uint8_t>(crc >> (24 - 8 * i));
    pos += 12 + length;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using rgbdmap::PngDecoder;
  if (size == 0) return 0;
  std::vector<std::uint8_t> png(data + 1, data + size);  // exactly sized: ASan sees overreads
  if (data[0] & 1) fixCrcs(png);
  const PngDecoder::Mode mode = data[0] & 2 ? PngDecoder::Mode::kDepth : PngDecoder::Mode::kColor;
  static PngDecoder decoder;  // buffers reused from input to input, as from frame to frame
  cv::Mat out;
  std::string error;
  if (decoder.decode(png.data(), png.size(), mode, out, error) == PngDecoder::Status::kDecoded &&
      out.type() != (mode == PngDecoder::Mode::kDepth ? CV_16UC1 : CV_8UC3))
    __builtin_trap();
  return 0;
}
