#include "rgbdmap/base/png_decoder.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>
#include <opencv2/core.hpp>
#include <optional>

#include "rgbdmap/base/png_format.hpp"

namespace rgbdmap {
namespace {

constexpr std::size_t kChunkOverhead = 12;  // length, type, CRC
constexpr std::uint32_t kMaxChunkLength = 0x7fffffff;
// Larger images are left to OpenCV, which refuses them in its own words: libpng's default
// PNG_USER_WIDTH_MAX / PNG_USER_HEIGHT_MAX and OpenCV's CV_IO_MAX_IMAGE_PIXELS.
constexpr std::uint32_t kMaxSide = 1000000;
constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 30;
// DEFLATE codes a 258-byte match in 2 bits at best, so no stream inflates to more than 1032
// times its size: a header promising more than that is refused before anything is allocated.
constexpr std::uint64_t kMaxInflateRatio = 1032;
constexpr std::uint64_t kZlibSlack = 64;

std::uint32_t bigEndian32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 | p[3];
}

bool isType(const std::uint8_t* type, const char (&name)[5]) {
  return std::memcmp(type, name, 4) == 0;
}

// PNG chunk types are four ASCII letters; anything else means the stream lost its framing.
bool isChunkType(const std::uint8_t* type) {
  return std::all_of(type, type + 4, [](std::uint8_t c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
  });
}

std::string typeName(const std::uint8_t* type) {
  return std::string(reinterpret_cast<const char*>(type), 4);
}

// The pixel layouts decoded here. Each converts one unfiltered pixel, in PNG byte order, to
// pixel x of an output row, exactly as cv::imdecode's libpng transforms would.
struct RgbToBgr {
  using Out = std::uint8_t;
  static constexpr int kBytes = 3;
  static void put(const std::uint8_t* p, Out* out, std::size_t x) {
    out[3 * x] = p[2];
    out[3 * x + 1] = p[1];
    out[3 * x + 2] = p[0];
  }
};
struct RgbaToBgr : RgbToBgr {  // png_set_strip_alpha: no compositing, the alpha byte is dropped
  static constexpr int kBytes = 4;
};
struct GreyToBgr {  // png_set_gray_to_rgb
  using Out = std::uint8_t;
  static constexpr int kBytes = 1;
  static void put(const std::uint8_t* p, Out* out, std::size_t x) {
    out[3 * x] = out[3 * x + 1] = out[3 * x + 2] = p[0];
  }
};
struct Grey16ToHost {  // PNG samples are big-endian
  using Out = std::uint16_t;
  static constexpr int kBytes = 2;
  static void put(const std::uint8_t* p, Out* out, std::size_t x) {
    out[x] = static_cast<std::uint16_t>(p[0] << 8 | p[1]);
  }
};

enum class Layout { kRgb8, kRgba8, kGrey8, kGrey16 };

// The layouts reproduced exactly; everything else (palette, interlacing, bit depths below 8,
// 16-bit colour, grey with alpha, 8-bit depth that the caller reports as wrong) goes to OpenCV.
std::optional<Layout> layoutFor(PngDecoder::Mode mode, int bit_depth, int colour_type,
                                int interlace) {
  if (interlace != 0) return std::nullopt;
  if (mode == PngDecoder::Mode::kDepth)
    return bit_depth == 16 && colour_type == 0 ? std::optional(Layout::kGrey16) : std::nullopt;
  if (bit_depth != 8) return std::nullopt;
  switch (colour_type) {
    case 0:
      return Layout::kGrey8;
    case 2:
      return Layout::kRgb8;
    case 6:
      return Layout::kRgba8;
    default:
      return std::nullopt;
  }
}

int bytesPerPixel(Layout layout) {
  switch (layout) {
    case Layout::kRgb8:
      return 3;
    case Layout::kRgba8:
      return 4;
    case Layout::kGrey8:
      return 1;
    case Layout::kGrey16:
      return 2;
  }
  return 0;
}

// The bit depths the PNG specification allows for each colour type.
bool validDepthForType(int bit_depth, int colour_type) {
  switch (colour_type) {
    case 0:
      return bit_depth == 1 || bit_depth == 2 || bit_depth == 4 || bit_depth == 8 ||
             bit_depth == 16;
    case 3:
      return bit_depth == 1 || bit_depth == 2 || bit_depth == 4 || bit_depth == 8;
    case 2:
    case 4:
    case 6:
      return bit_depth == 8 || bit_depth == 16;
    default:
      return false;
  }
}

enum Filter : std::uint8_t { kNone = 0, kSub = 1, kUp = 2, kAverage = 3, kPaeth = 4 };

// Sub, Average and Paeth predict each byte from the byte one pixel to the left, a serial chain
// that no vector unit shortens. The left and upper-left pixels are carried in registers (a
// reload of the byte just stored would wait on store forwarding), and the finished pixel is
// converted while it is at hand. The unfiltered row is stored back: it is the next row's prior.
template <class Format, class Predict>
void unfilterPixels(std::uint8_t* row, const std::uint8_t* prior, std::size_t width,
                    typename Format::Out* out, Predict predict) {
  constexpr int kBytes = Format::kBytes;
  std::uint8_t left[kBytes] = {};
  std::uint8_t upper_left[kBytes] = {};
  for (std::size_t x = 0; x < width; ++x) {
    std::uint8_t* px = row + x * kBytes;
    const std::uint8_t* up = prior + x * kBytes;
    for (int k = 0; k < kBytes; ++k) {
      left[k] = static_cast<std::uint8_t>(px[k] + predict(left[k], up[k], upper_left[k]));
      upper_left[k] = up[k];
      px[k] = left[k];
    }
    Format::put(left, out, x);
  }
}

template <class Format>
void decodeRow(std::uint8_t filter, std::uint8_t* row, const std::uint8_t* prior, std::size_t width,
               typename Format::Out* out) {
  constexpr int kBytes = Format::kBytes;
  switch (filter) {
    case kSub:
      return unfilterPixels<Format>(row, prior, width, out, [](int a, int, int) { return a; });
    case kAverage:
      return unfilterPixels<Format>(row, prior, width, out,
                                    [](int a, int b, int) { return (a + b) >> 1; });
    case kPaeth:
      return unfilterPixels<Format>(row, prior, width, out,
                                    [](int a, int b, int c) { return pngPaeth(a, b, c); });
    case kUp:  // no chain: a plain loop the compiler vectorises
      for (std::size_t i = 0; i < width * kBytes; ++i)
        row[i] = static_cast<std::uint8_t>(row[i] + prior[i]);
      break;
    default:  // kNone
      break;
  }
  for (std::size_t x = 0; x < width; ++x) Format::put(row + x * kBytes, out, x);
}

template <class Format>
void decodeImage(std::uint8_t* scanlines, std::size_t width, std::size_t height,
                 const std::uint8_t* zero_row, cv::Mat& out) {
  const std::size_t stride = 1 + width * Format::kBytes;
  const std::uint8_t* prior = zero_row;
  for (std::size_t y = 0; y < height; ++y) {
    std::uint8_t* line = scanlines + y * stride;
    decodeRow<Format>(line[0], line + 1, prior, width,
                      out.ptr<typename Format::Out>(static_cast<int>(y)));
    prior = line + 1;
  }
}

}  // namespace

void PngDecoder::FreeDecompressor::operator()(libdeflate_decompressor* d) const {
  libdeflate_free_decompressor(d);
}

PngDecoder::PngDecoder() : inflater_(libdeflate_alloc_decompressor()) {
  if (!inflater_) throw std::bad_alloc();
}

PngDecoder::~PngDecoder() = default;
PngDecoder::PngDecoder(PngDecoder&&) noexcept = default;
PngDecoder& PngDecoder::operator=(PngDecoder&&) noexcept = default;

namespace {

// What the chunks give: the image's size and layout and how much image data (IDAT) there is.
struct PngImage {
  std::uint32_t width = 0, height = 0;
  std::optional<Layout> layout;
  std::size_t compressed_size = 0;
};

// The IHDR chunk's `body` (13 bytes): the image's size and layout. kDecoded when it is an image
// this decoder decodes.
PngDecoder::Status readHeader(const std::uint8_t* body, PngDecoder::Mode mode, PngImage& image,
                              std::string& error) {
  const auto corrupt = [&](const std::string& why) {
    error = why;
    return PngDecoder::Status::kCorrupt;
  };
  image.width = bigEndian32(body);
  image.height = bigEndian32(body + 4);
  const int bit_depth = body[8], colour_type = body[9], interlace = body[12];
  if (image.width == 0 || image.height == 0 || image.width > kMaxChunkLength ||
      image.height > kMaxChunkLength)
    return corrupt("invalid image size " + std::to_string(image.width) + "x" +
                   std::to_string(image.height));
  if (!validDepthForType(bit_depth, colour_type))
    return corrupt("invalid bit depth " + std::to_string(bit_depth) + " for colour type " +
                   std::to_string(colour_type));
  if (body[10] != 0 || body[11] != 0 || interlace > 1)
    return corrupt("unknown compression, filter or interlace method in IHDR");
  image.layout = layoutFor(mode, bit_depth, colour_type, interlace);
  if (!image.layout || image.width > kMaxSide || image.height > kMaxSide ||
      std::uint64_t{image.width} * image.height > kMaxPixels)
    return PngDecoder::Status::kUnsupported;
  return PngDecoder::Status::kDecoded;
}

// The chunks: IHDR first, then any, with the image data in consecutive IDAT chunks (appended to
// `compressed`), up to IEND. Only critical chunks (IHDR, PLTE, IDAT, IEND) have their CRC
// checked: libpng discards an ancillary chunk with a bad CRC and decodes the image regardless,
// and none of them changes what is decoded here. kDecoded when they hold an image this decoder
// decodes.
PngDecoder::Status readChunks(const std::uint8_t* data, std::size_t size, PngDecoder::Mode mode,
                              std::vector<std::uint8_t>& compressed, PngImage& image,
                              std::string& error) {
  const auto corrupt = [&](const std::string& why) {
    error = why;
    return PngDecoder::Status::kCorrupt;
  };
  enum class Idat { kBefore, kIn, kAfter } idat = Idat::kBefore;
  for (std::size_t pos = sizeof(kPngSignature);;) {
    // Messages are built only on failure: a frame's decoding allocates nothing.
    const auto at = [pos] { return " at byte " + std::to_string(pos); };
    if (size - pos < kChunkOverhead)
      return corrupt(pos == size ? "truncated: no IEND chunk"
                                 : "truncated: the chunk header" + at() + " is cut short");
    const std::uint32_t length = bigEndian32(data + pos);
    const std::uint8_t* type = data + pos + 4;
    const std::uint8_t* body = data + pos + 8;
    if (!isChunkType(type)) return corrupt("invalid chunk type" + at());
    const auto name = [&] { return "the " + typeName(type) + " chunk" + at(); };
    if (length > kMaxChunkLength)
      return corrupt(name() + " claims " + std::to_string(length) + " bytes");
    if (length > size - pos - kChunkOverhead)
      return corrupt("truncated: " + name() + " holds " + std::to_string(length) + " bytes, " +
                     std::to_string(size - pos - kChunkOverhead) + " are left");
    const bool critical = (type[0] & 0x20) == 0;
    if (critical && libdeflate_crc32(0, type, length + 4) != bigEndian32(body + length))
      return corrupt("bad CRC in " + name());

    if (image.width == 0) {  // the first chunk
      if (!isType(type, "IHDR")) return corrupt("the first chunk is " + typeName(type));
      if (length != 13)
        return corrupt(name() + " has " + std::to_string(length) + " bytes, not 13");
      const PngDecoder::Status header = readHeader(body, mode, image, error);
      if (header != PngDecoder::Status::kDecoded) return header;
    } else if (isType(type, "IHDR")) {
      return corrupt("a second IHDR chunk" + at());
    } else if (isType(type, "IDAT")) {
      // libpng reads image data split by other chunks only as far as it needs it.
      if (idat == Idat::kAfter) return PngDecoder::Status::kUnsupported;
      idat = Idat::kIn;
      if (compressed.size() < image.compressed_size + length)
        compressed.resize(image.compressed_size + length);
      std::memcpy(compressed.data() + image.compressed_size, body, length);
      image.compressed_size += length;
    } else if (isType(type, "IEND")) {
      break;
    } else {
      if (idat == Idat::kIn) idat = Idat::kAfter;
      // libpng refuses unknown critical chunks; PLTE is a suggestion for RGB and is ignored
      // (as libpng ignores it) for grey.
      if (critical && !isType(type, "PLTE")) return PngDecoder::Status::kUnsupported;
    }
    pos += kChunkOverhead + length;
  }
  if (idat == Idat::kBefore) return corrupt("no IDAT chunk");
  return PngDecoder::Status::kDecoded;
}

}  // namespace

PngDecoder::Status PngDecoder::decode(const std::uint8_t* data, std::size_t size, Mode mode,
                                      cv::Mat& out, std::string& error) {
  const auto corrupt = [&](const std::string& why) {
    error = why;
    return Status::kCorrupt;
  };
  if (size < sizeof(kPngSignature) || !std::equal(kPngSignature, kPngSignature + 8, data))
    return corrupt("not a PNG file (bad signature)");
  PngImage image;
  const Status read = readChunks(data, size, mode, compressed_, image, error);
  if (read != Status::kDecoded) return read;
  const std::uint32_t width = image.width, height = image.height;
  const Layout layout = *image.layout;
  const std::size_t compressed_size = image.compressed_size;

  const std::size_t pixel_bytes = static_cast<std::size_t>(bytesPerPixel(layout));
  const std::size_t stride = 1 + std::size_t{width} * pixel_bytes;
  const std::size_t scan_size = stride * height;
  const auto image_size = [&] { return std::to_string(width) + "x" + std::to_string(height); };
  if (scan_size > (compressed_size + kZlibSlack) * kMaxInflateRatio)
    return corrupt(std::to_string(compressed_size) + " bytes of image data cannot hold a " +
                   image_size() + " image");
  try {
    if (scanlines_.size() < scan_size) scanlines_.resize(scan_size);
  } catch (const std::bad_alloc&) {
    return corrupt("no memory for a " + image_size() + " image");
  }
  // With no actual-size pointer libdeflate insists on exactly scan_size bytes, and it checks
  // the stream's Adler-32.
  switch (libdeflate_zlib_decompress(inflater_.get(), compressed_.data(), compressed_size,
                                     scanlines_.data(), scan_size, nullptr)) {
    case LIBDEFLATE_SUCCESS:
      break;
    case LIBDEFLATE_SHORT_OUTPUT:
      return corrupt("the image data inflates to fewer than the " + std::to_string(scan_size) +
                     " bytes of a " + image_size() + " image");
    case LIBDEFLATE_INSUFFICIENT_SPACE:
      // libpng decodes such a file with a warning ("Too much image data"): it stays OpenCV's.
      return Status::kUnsupported;
    default:
      return corrupt("the compressed image data is corrupt (bad deflate stream or checksum)");
  }
  // Checked before `out` is touched, so that a failure leaves it as it was.
  for (std::size_t y = 0; y < height; ++y) {
    const std::uint8_t filter = scanlines_[y * stride];
    if (filter > kPaeth)
      return corrupt("row " + std::to_string(y) + " has filter type " + std::to_string(filter) +
                     " (0 to 4 are defined)");
  }
  if (zero_row_.size() < stride) zero_row_.resize(stride);  // only ever read
  try {
    out.create(static_cast<int>(height), static_cast<int>(width),
               layout == Layout::kGrey16 ? CV_16UC1 : CV_8UC3);
  } catch (const cv::Exception&) {
    return corrupt("no memory for a " + image_size() + " image");
  }

  switch (layout) {
    case Layout::kRgb8:
      decodeImage<RgbToBgr>(scanlines_.data(), width, height, zero_row_.data(), out);
      break;
    case Layout::kRgba8:
      decodeImage<RgbaToBgr>(scanlines_.data(), width, height, zero_row_.data(), out);
      break;
    case Layout::kGrey8:
      decodeImage<GreyToBgr>(scanlines_.data(), width, height, zero_row_.data(), out);
      break;
    case Layout::kGrey16:
      decodeImage<Grey16ToHost>(scanlines_.data(), width, height, zero_row_.data(), out);
      break;
  }
  return Status::kDecoded;
}

}  // namespace rgbdmap
