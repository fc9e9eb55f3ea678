#include "rgbdmap/base/png_encoder.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "rgbdmap/base/png_format.hpp"

namespace rgbdmap {
namespace {

void putBigEndian(std::vector<std::uint8_t>& out, std::uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8)
    out.push_back(static_cast<std::uint8_t>(value >> shift));
}

// Appends one chunk: length, type, data, CRC of type and data.
void putChunk(std::vector<std::uint8_t>& out, const char (&type)[5], const std::uint8_t* data,
              std::size_t size) {
  putBigEndian(out, static_cast<std::uint32_t>(size));
  const std::size_t type_at = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data, data + size);
  const std::uint32_t crc = libdeflate_crc32(0, out.data() + type_at, size + 4);
  putBigEndian(out, crc);
}

// Sum of the filtered bytes taken as signed: small when the filter predicted the row well.
std::uint64_t cost(const std::uint8_t* row, std::size_t n) {
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < n; ++i)
    sum += static_cast<std::uint64_t>(std::abs(static_cast<std::int8_t>(row[i])));
  return sum;
}

}  // namespace

void PngEncoder::FreeCompressor::operator()(libdeflate_compressor* c) const {
  libdeflate_free_compressor(c);
}

PngEncoder::PngEncoder(int level)
    : deflater_(libdeflate_alloc_compressor(std::clamp(level, 0, 9))) {}
PngEncoder::~PngEncoder() = default;
PngEncoder::PngEncoder(PngEncoder&&) noexcept = default;
PngEncoder& PngEncoder::operator=(PngEncoder&&) noexcept = default;

bool PngEncoder::supports(const cv::Mat& image) {
  switch (image.type()) {
    case CV_8UC1:
    case CV_8UC3:
    case CV_8UC4:
    case CV_16UC1:
    case CV_16UC3:
      return !image.empty();
    default:
      return false;
  }
}

namespace {

// The image's rows as PNG samples: RGB(A) order, big-endian 16-bit values.
void toPngSamples(const cv::Mat& image, std::size_t row_bytes, std::vector<std::uint8_t>& raw) {
  const int channels = image.channels();
  raw.resize(row_bytes * static_cast<std::size_t>(image.rows));
  for (int v = 0; v < image.rows; ++v) {
    std::uint8_t* out = raw.data() + static_cast<std::size_t>(v) * row_bytes;
    if (image.elemSize1() == 1) {
      const std::uint8_t* in = image.ptr<std::uint8_t>(v);
      if (channels == 1) {
        std::memcpy(out, in, row_bytes);
      } else {
        for (int u = 0; u < image.cols; ++u, in += channels, out += channels) {
          out[0] = in[2];
          out[1] = in[1];
          out[2] = in[0];
          if (channels == 4) out[3] = in[3];
        }
      }
    } else {
      const std::uint16_t* in = image.ptr<std::uint16_t>(v);
      for (int u = 0; u < image.cols; ++u, in += channels) {
        for (int c = 0; c < channels; ++c) {
          const std::uint16_t value = in[channels == 3 ? 2 - c : c];
          *out++ = static_cast<std::uint8_t>(value >> 8);
          *out++ = static_cast<std::uint8_t>(value & 0xff);
        }
      }
    }
  }
}

// The five filters' outputs for one row, one after another in `out` (5 * n bytes). The pointers
// never alias: saying so lets the loop vectorise.
void predictRow(const std::uint8_t* __restrict row, const std::uint8_t* __restrict up,
                std::size_t n, std::size_t bpp, std::uint8_t* __restrict out) {
  std::uint8_t* __restrict none = out;
  std::uint8_t* __restrict sub = out + n;
  std::uint8_t* __restrict above = out + 2 * n;
  std::uint8_t* __restrict average = out + 3 * n;
  std::uint8_t* __restrict best_guess = out + 4 * n;
  // The first pixel has no left neighbour; without that test the rest vectorises.
  const std::size_t first = std::min(bpp, n);
  for (std::size_t i = 0; i < first; ++i) {
    none[i] = sub[i] = row[i];
    above[i] = static_cast<std::uint8_t>(row[i] - up[i]);
    average[i] = static_cast<std::uint8_t>(row[i] - (up[i] >> 1));
    best_guess[i] = static_cast<std::uint8_t>(row[i] - up[i]);  // Paeth of (0, b, 0) is b
  }
  for (std::size_t i = first; i < n; ++i) {
    const int a = row[i - bpp], b = up[i], c = up[i - bpp];
    none[i] = row[i];
    sub[i] = static_cast<std::uint8_t>(row[i] - a);
    above[i] = static_cast<std::uint8_t>(row[i] - b);
    average[i] = static_cast<std::uint8_t>(row[i] - ((a + b) >> 1));
    best_guess[i] = static_cast<std::uint8_t>(row[i] - pngPaeth(a, b, c));
  }
}

// Filters: each row of `raw` takes the one (None, Sub, Up, Average, Paeth) whose output costs
// least, written after its filter byte to `filtered`. `bpp`: bytes back to the corresponding byte
// of the left pixel; `candidate`: room for the five filters' rows.
void filterRows(const std::vector<std::uint8_t>& raw, std::size_t row_bytes, std::size_t rows,
                std::size_t bpp, std::vector<std::uint8_t>& filtered,
                std::vector<std::uint8_t>& candidate) {
  filtered.resize((row_bytes + 1) * rows);
  candidate.resize(5 * row_bytes);
  const std::vector<std::uint8_t> zero(row_bytes, 0);
  for (std::size_t v = 0; v < rows; ++v) {
    const std::uint8_t* row = raw.data() + v * row_bytes;
    const std::uint8_t* up = v == 0 ? zero.data() : row - row_bytes;
    predictRow(row, up, row_bytes, bpp, candidate.data());
    int best = 0;
    std::uint64_t best_cost = UINT64_MAX;
    for (int f = 0; f < 5; ++f) {
      const std::uint64_t c = cost(candidate.data() + f * row_bytes, row_bytes);
      if (c < best_cost) {
        best_cost = c;
        best = f;
      }
    }
    std::uint8_t* out = filtered.data() + v * (row_bytes + 1);
    out[0] = static_cast<std::uint8_t>(best);
    std::memcpy(out + 1, candidate.data() + best * row_bytes, row_bytes);
  }
}

}  // namespace

bool PngEncoder::encode(const cv::Mat& image, std::vector<std::uint8_t>& png, std::string& error) {
  if (!supports(image)) {
    error = "PNG holds 8-bit grey, colour or colour with alpha, or 16-bit grey or colour images";
    return false;
  }
  if (!deflater_) {
    error = "cannot set up PNG compression (out of memory)";
    return false;
  }
  const int channels = image.channels();
  const int sample_bytes = static_cast<int>(image.elemSize1());
  const std::size_t pixel_bytes = static_cast<std::size_t>(channels) * sample_bytes;
  const std::size_t row_bytes = pixel_bytes * static_cast<std::size_t>(image.cols);
  const std::size_t rows = static_cast<std::size_t>(image.rows);

  toPngSamples(image, row_bytes, raw_);
  filterRows(raw_, row_bytes, rows, pixel_bytes, filtered_, candidate_);

  png.clear();
  png.insert(png.end(), std::begin(kPngSignature), std::end(kPngSignature));
  std::uint8_t header[13];
  const std::uint32_t width = static_cast<std::uint32_t>(image.cols);
  const std::uint32_t height = static_cast<std::uint32_t>(image.rows);
  for (int i = 0; i < 4; ++i) {
    header[i] = static_cast<std::uint8_t>(width >> (24 - 8 * i));
    header[4 + i] = static_cast<std::uint8_t>(height >> (24 - 8 * i));
  }
  header[8] = static_cast<std::uint8_t>(8 * sample_bytes);
  header[9] = channels == 1 ? 0 : channels == 3 ? 2 : 6;  // grey, RGB, RGBA
  header[10] = header[11] = header[12] = 0;  // deflate, adaptive filtering, not interlaced
  putChunk(png, "IHDR", header, sizeof header);

  std::vector<std::uint8_t>& compressed = candidate_;  // free again now
  compressed.resize(libdeflate_zlib_compress_bound(deflater_.get(), filtered_.size()));
  const std::size_t size = libdeflate_zlib_compress(
      deflater_.get(), filtered_.data(), filtered_.size(), compressed.data(), compressed.size());
  if (size == 0) {
    error = "PNG compression failed";
    return false;
  }
  putChunk(png, "IDAT", compressed.data(), size);
  putChunk(png, "IEND", nullptr, 0);
  return true;
}

}  // namespace rgbdmap
