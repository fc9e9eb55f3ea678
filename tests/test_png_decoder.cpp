// PngDecoder against cv::imdecode, which it must reproduce byte for byte: every frame of the
// shared TUM folders, hand-made PNGs with every filter and the layouts it decodes, the PNGs it
// leaves to OpenCV, and damaged files (truncated at every chunk boundary, bytes flipped), which
// must give an error or an image and never a crash (ASan runs this too).
#include <gtest/gtest.h>
#include <libdeflate.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <tuple>

#include "rgbdmap/base/png_decoder.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;
using Mode = PngDecoder::Mode;
using Status = PngDecoder::Status;

using test::kRpy;
using test::kXyz;

Bytes readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const Bytes& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

cv::Mat openCv(const Bytes& png, Mode mode) {
  return cv::imdecode(png, mode == Mode::kDepth ? cv::IMREAD_UNCHANGED : cv::IMREAD_COLOR);
}

// Same size, type and bytes.
::testing::AssertionResult identical(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type())
    return ::testing::AssertionFailure()
           << "size or type differs: " << a.cols << "x" << a.rows << " type " << a.type() << " vs "
           << b.cols << "x" << b.rows << " type " << b.type();
  for (int y = 0; y < a.rows; ++y)
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0)
      return ::testing::AssertionFailure() << "row " << y << " differs";
  return ::testing::AssertionSuccess();
}

void putBigEndian32(Bytes& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

void appendChunk(Bytes& png, const std::string& type, const Bytes& body) {
  putBigEndian32(png, static_cast<std::uint32_t>(body.size()));
  const std::size_t start = png.size();
  png.insert(png.end(), type.begin(), type.end());
  png.insert(png.end(), body.begin(), body.end());
  putBigEndian32(png, libdeflate_crc32(0, png.data() + start, png.size() - start));
}

Bytes zlibCompress(const Bytes& raw) {
  libdeflate_compressor* compressor = libdeflate_alloc_compressor(6);
  Bytes out(libdeflate_zlib_compress_bound(compressor, raw.size()));
  out.resize(libdeflate_zlib_compress(compressor, raw.data(), raw.size(), out.data(), out.size()));
  libdeflate_free_compressor(compressor);
  return out;
}

int paethPredictor(int a, int b, int c) {  // as the PNG specification writes it
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

// Scanlines of `rows` (each `row_bytes` of samples in PNG order), row y filtered with
// filter_of(y) for pixels of `pixel_bytes`.
Bytes filterRows(const std::vector<Bytes>& rows, std::size_t pixel_bytes,
                 const std::function<int(std::size_t)>& filter_of) {
  Bytes out;
  for (std::size_t y = 0; y < rows.size(); ++y) {
    const int filter = filter_of(y);
    out.push_back(static_cast<std::uint8_t>(filter));
    for (std::size_t i = 0; i < rows[y].size(); ++i) {
      const int a = i >= pixel_bytes ? rows[y][i - pixel_bytes] : 0;
      const int b = y > 0 ? rows[y - 1][i] : 0;
      const int c = y > 0 && i >= pixel_bytes ? rows[y - 1][i - pixel_bytes] : 0;
      const int predicted[] = {0, a, b, (a + b) / 2, paethPredictor(a, b, c)};
      // Filter types past Paeth (for the damage tests) are written unpredicted.
      out.push_back(static_cast<std::uint8_t>(rows[y][i] - (filter <= 4 ? predicted[filter] : 0)));
    }
  }
  return out;
}

// A PNG made by hand, so that every filter, layout and chunk arrangement can be had.
struct PngSpec {
  int width = 37;  // odd sizes: no row or pass is a multiple of anything
  int height = 23;
  int bit_depth = 8;
  int colour_type = 2;
  bool interlaced = false;
  std::function<int(std::size_t)> filter_of = [](std::size_t y) { return static_cast<int>(y % 5); };
  std::size_t idat_piece = 100;                       // bytes per IDAT chunk
  std::vector<std::pair<std::string, Bytes>> before;  // chunks between IHDR and IDAT
  std::uint32_t seed = 1;
};

int channelsOf(int colour_type) {
  const int channels[] = {1, 0, 3, 1, 2, 0, 4};
  return channels[colour_type];
}

Bytes makePng(const PngSpec& spec) {
  std::mt19937 random(spec.seed);
  const int bits_per_pixel = spec.bit_depth * channelsOf(spec.colour_type);
  const std::size_t pixel_bytes = static_cast<std::size_t>(std::max(1, bits_per_pixel / 8));
  // Noise on a gradient: smooth enough for every Paeth choice to come up, rough enough to
  // exercise wrap-around.
  const auto image_rows = [&](int width, int height, int x0, int y0, int dx, int dy) {
    std::vector<Bytes> rows;
    for (int y = y0; y < height; y += dy) {
      Bytes row;
      int bits = 0, acc = 0;
      for (int x = x0; x < width; x += dx) {
        for (int s = 0; s < bits_per_pixel / std::min(spec.bit_depth, 8); ++s) {
          const int value = (x * 7 + y * 3 + s * 50 + static_cast<int>(random() % 9)) & 0xff;
          if (spec.bit_depth >= 8) {
            row.push_back(static_cast<std::uint8_t>(value));
            continue;
          }
          acc = acc << spec.bit_depth | (value & ((1 << spec.bit_depth) - 1));
          if ((bits += spec.bit_depth) == 8) row.push_back(static_cast<std::uint8_t>(acc));
          if (bits == 8) bits = acc = 0;
        }
      }
      if (bits > 0) row.push_back(static_cast<std::uint8_t>(acc << (8 - bits)));
      if (!row.empty()) rows.push_back(row);
    }
    return rows;
  };
  Bytes scanlines;
  if (!spec.interlaced) {
    scanlines =
        filterRows(image_rows(spec.width, spec.height, 0, 0, 1, 1), pixel_bytes, spec.filter_of);
  } else {  // Adam7: seven passes, each a small image of its own
    const int passes[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                              {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};
    for (const auto& p : passes) {
      const Bytes pass = filterRows(image_rows(spec.width, spec.height, p[0], p[1], p[2], p[3]),
                                    pixel_bytes, spec.filter_of);
      scanlines.insert(scanlines.end(), pass.begin(), pass.end());
    }
  }
  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  Bytes header;
  putBigEndian32(header, static_cast<std::uint32_t>(spec.width));
  putBigEndian32(header, static_cast<std::uint32_t>(spec.height));
  header.insert(header.end(), {static_cast<std::uint8_t>(spec.bit_depth),
                               static_cast<std::uint8_t>(spec.colour_type), 0, 0,
                               static_cast<std::uint8_t>(spec.interlaced ? 1 : 0)});
  appendChunk(png, "IHDR", header);
  for (const auto& [type, body] : spec.before) appendChunk(png, type, body);
  const Bytes compressed = zlibCompress(scanlines);
  for (std::size_t at = 0; at < compressed.size(); at += spec.idat_piece)
    appendChunk(png, "IDAT",
                Bytes(compressed.begin() + static_cast<std::ptrdiff_t>(at),
                      compressed.begin() + static_cast<std::ptrdiff_t>(
                                               std::min(compressed.size(), at + spec.idat_piece))));
  appendChunk(png, "IEND", {});
  return png;
}

Bytes palette(int entries_count) {
  Bytes entries;
  for (int i = 0; i < entries_count; ++i)
    entries.insert(entries.end(), {static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(255 - i),
                                   static_cast<std::uint8_t>(i * 7)});
  return entries;
}

// Decodes with a fresh decoder and expects OpenCV's image.
void expectLikeOpenCv(const Bytes& png, Mode mode, Status expected = Status::kDecoded) {
  PngDecoder decoder;
  cv::Mat out;
  std::string error;
  ASSERT_EQ(decoder.decode(png.data(), png.size(), mode, out, error), expected) << error;
  if (expected == Status::kDecoded) {
    const cv::Mat reference = openCv(png, mode);
    ASSERT_FALSE(reference.empty());
    EXPECT_TRUE(identical(out, reference));
  }
}

std::vector<std::string> pngsIn(const std::string& folder) {
  std::vector<std::string> paths;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().extension() == ".png") paths.push_back(entry.path());
  std::sort(paths.begin(), paths.end());
  return paths;
}

TEST(PngDecoder, DecodesEveryTumFrameLikeOpenCv) {
  PngDecoder decoder;  // one decoder and one output per kind, as TumSequence holds them
  cv::Mat color, depth;
  std::size_t decoded = 0;
  for (const std::string& name : {kXyz, kRpy}) {
    for (const auto& [folder, mode] : {std::pair{"/rgb", Mode::kColor}, {"/depth", Mode::kDepth}}) {
      cv::Mat& out = mode == Mode::kColor ? color : depth;
      for (const std::string& path : pngsIn(test::tumDir(name) + folder)) {
        const Bytes png = readBytes(path);
        const std::uint8_t* buffer_before = out.data;
        std::string error;
        ASSERT_EQ(decoder.decode(png.data(), png.size(), mode, out, error), Status::kDecoded)
            << path << ": " << error;
        ASSERT_TRUE(identical(out, openCv(png, mode))) << path;
        // Frames of one size land in the same buffer: no allocation per frame.
        if (buffer_before != nullptr) {
          EXPECT_EQ(out.data, buffer_before) << path;
        }
        ++decoded;
      }
    }
  }
  EXPECT_GT(decoded, 200u);
}

TEST(PngDecoder, EveryFilterInEveryLayout) {
  // {bit depth, colour type, mode}: RGB, RGBA, grey as colour; 16-bit grey as depth.
  const std::tuple<int, int, Mode> layouts[] = {
      {8, 2, Mode::kColor}, {8, 6, Mode::kColor}, {8, 0, Mode::kColor}, {16, 0, Mode::kDepth}};
  for (const auto& [bit_depth, colour_type, mode] : layouts) {
    for (int filter = 0; filter <= 5; ++filter) {  // 5: every row a different filter
      SCOPED_TRACE("bit depth " + std::to_string(bit_depth) + ", colour type " +
                   std::to_string(colour_type) + ", filter " + std::to_string(filter));
      PngSpec spec;
      spec.bit_depth = bit_depth;
      spec.colour_type = colour_type;
      spec.filter_of = [filter](std::size_t y) {
        return filter < 5 ? filter : static_cast<int>(y % 5);
      };
      spec.seed = static_cast<std::uint32_t>(filter + 10 * colour_type);
      expectLikeOpenCv(makePng(spec), mode);
    }
  }
}

TEST(PngDecoder, OneRowOnePixelAndOneBigIdat) {
  for (const auto& [w, h] : {std::pair{1, 1}, {1, 9}, {9, 1}}) {
    PngSpec spec;
    spec.width = w;
    spec.height = h;
    expectLikeOpenCv(makePng(spec), Mode::kColor);
  }
  PngSpec spec;
  spec.idat_piece = 1 << 20;
  expectLikeOpenCv(makePng(spec), Mode::kColor);
}

TEST(PngDecoder, ImagesOpenCvWroteDecodeAlike) {
  cv::Mat bgra(31, 45, CV_8UC4), grey(31, 45, CV_8UC1), bgr(31, 45, CV_8UC3),
      depth(31, 45, CV_16UC1);
  cv::RNG rng(7);
  for (cv::Mat* m : {&bgra, &grey, &bgr}) rng.fill(*m, cv::RNG::UNIFORM, 0, 256);
  rng.fill(depth, cv::RNG::UNIFORM, 0, 65536);
  for (const int level : {0, 1, 9}) {
    const std::vector<int> params = {cv::IMWRITE_PNG_COMPRESSION, level};
    Bytes png;
    for (const cv::Mat* m : {&bgra, &grey, &bgr}) {
      ASSERT_TRUE(cv::imencode(".png", *m, png, params));
      expectLikeOpenCv(png, Mode::kColor);
    }
    ASSERT_TRUE(cv::imencode(".png", depth, png, params));
    expectLikeOpenCv(png, Mode::kDepth);
  }
}

TEST(PngDecoder, AncillaryChunksChangeNothingAsInOpenCv) {
  // OpenCV asks libpng for no gamma correction, colour management, background or
  // transparency handling: gAMA, cHRM, sRGB, iCCP, bKGD, sBIT, tRNS leave the pixels alone.
  const Bytes gamma = {0, 0, 0x27, 0x10};  // 0.01: a very visible change were it applied
  PngSpec rgb;
  rgb.before = {{"gAMA", gamma},
                {"sBIT", {5, 6, 5}},
                {"PLTE", palette(256)},  // a suggested palette for an RGB image
                {"bKGD", {0, 255, 0, 0, 0, 255}},
                {"tRNS", {0, 10, 0, 20, 0, 30}},
                {"tEXt", {'a', 0, 'b'}}};
  expectLikeOpenCv(makePng(rgb), Mode::kColor);
  PngSpec rgba;
  rgba.colour_type = 6;
  rgba.before = {{"gAMA", gamma}, {"sBIT", {5, 6, 5, 1}}, {"bKGD", {0, 255, 0, 0, 0, 255}}};
  expectLikeOpenCv(makePng(rgba), Mode::kColor);
  PngSpec grey;
  grey.colour_type = 0;
  grey.before = {{"gAMA", gamma}, {"sBIT", {3}}, {"bKGD", {0, 200}}, {"tRNS", {0, 7}}};
  expectLikeOpenCv(makePng(grey), Mode::kColor);
  PngSpec depth;
  depth.bit_depth = 16;
  depth.colour_type = 0;
  depth.before = {{"gAMA", gamma}, {"sBIT", {12}}, {"tRNS", {0, 0}}};
  expectLikeOpenCv(makePng(depth), Mode::kDepth);
}

// The PNGs left to OpenCV: the decoder says so and leaves `out` alone; TumSequence then gives
// OpenCV's image.
TEST(PngDecoder, LeavesOtherPngsToOpenCv) {
  struct Case {
    std::string what;
    PngSpec spec;
    Mode mode;
  };
  std::vector<Case> cases;
  const auto add = [&](const std::string& what, int bit_depth, int colour_type, bool interlaced,
                       Mode mode) {
    PngSpec spec;
    spec.bit_depth = bit_depth;
    spec.colour_type = colour_type;
    spec.interlaced = interlaced;
    if (colour_type == 3) spec.before = {{"PLTE", palette(1 << bit_depth)}};
    cases.push_back({what, spec, mode});
  };
  add("interlaced RGB", 8, 2, true, Mode::kColor);
  add("interlaced 16-bit depth", 16, 0, true, Mode::kDepth);
  add("palette", 8, 3, false, Mode::kColor);
  add("4-bit palette", 4, 3, false, Mode::kColor);
  add("1-bit grey", 1, 0, false, Mode::kColor);
  add("grey with alpha", 8, 4, false, Mode::kColor);
  add("16-bit RGB", 16, 2, false, Mode::kColor);
  add("16-bit RGBA", 16, 6, false, Mode::kColor);
  add("16-bit grey as colour", 16, 0, false, Mode::kColor);
  add("8-bit depth", 8, 0, false, Mode::kDepth);
  add("RGB depth", 8, 2, false, Mode::kDepth);

  const std::string dir = test::freshDir();
  fs::create_directories(dir + "/rgb");
  fs::create_directories(dir + "/depth");
  {
    std::ofstream(dir + "/rgb.txt") << "1.0 rgb/a.png\n";
    std::ofstream(dir + "/depth.txt") << "1.0 depth/a.png\n";
  }
  PngSpec plain_depth;
  plain_depth.bit_depth = 16;
  plain_depth.colour_type = 0;
  PngSpec plain_colour;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const Bytes png = makePng(c.spec);
    PngDecoder decoder;
    cv::Mat out(3, 3, CV_8UC1, cv::Scalar(42));
    const cv::Mat before = out.clone();
    std::string error;
    ASSERT_EQ(decoder.decode(png.data(), png.size(), c.mode, out, error), Status::kUnsupported);
    EXPECT_TRUE(identical(out, before));
    if (c.mode == Mode::kDepth && c.spec.bit_depth != 16) continue;  // TumSequence refuses it
    // Through TumSequence, the fallback: OpenCV's image, exactly.
    writeBytes(dir + (c.mode == Mode::kDepth ? "/depth/a.png" : "/rgb/a.png"), png);
    writeBytes(dir + (c.mode == Mode::kDepth ? "/rgb/a.png" : "/depth/a.png"),
               makePng(c.mode == Mode::kDepth ? plain_colour : plain_depth));
    TumSequence sequence(dir);
    Frame frame;
    ASSERT_TRUE(sequence.load(0, frame, error)) << error;
    if (c.mode == Mode::kColor) {
      EXPECT_TRUE(identical(frame.color, openCv(png, Mode::kColor)));
    } else {
      cv::Mat metres;
      openCv(png, Mode::kDepth).convertTo(metres, CV_32F, 1.0 / 5000.0);
      EXPECT_TRUE(identical(frame.depth, metres));
    }
  }
}

// --- Damaged files -----------------------------------------------------------------------

struct Chunk {
  std::size_t offset;  // of its length field
  std::size_t length;  // of its data
  std::string type;
};

std::vector<Chunk> chunksOf(const Bytes& png) {
  std::vector<Chunk> chunks;
  for (std::size_t pos = 8; pos + 12 <= png.size();) {
    const std::size_t length = std::size_t{png[pos]} << 24 | std::size_t{png[pos + 1]} << 16 |
                               std::size_t{png[pos + 2]} << 8 | png[pos + 3];
    chunks.push_back({pos, length, std::string(png.begin() + pos + 4, png.begin() + pos + 8)});
    pos += 12 + length;
  }
  return chunks;
}

// Rewrites a chunk's CRC after its data was changed on purpose.
void fixCrc(Bytes& png, const Chunk& c) {
  const std::uint32_t crc = libdeflate_crc32(0, png.data() + c.offset + 4, c.length + 4);
  for (int i = 0; i < 4; ++i)
    png[c.offset + 8 + c.length + i] = static_cast<std::uint8_t>(crc >> (24 - 8 * i));
}

// Decodes damaged bytes (in a buffer of exactly their size, so that ASan sees any overread):
// the result is an error with a reason, an image of the right type, or OpenCV's business.
Status decodeDamaged(PngDecoder& decoder, const Bytes& png, Mode mode, cv::Mat& out,
                     std::string& error) {
  const std::unique_ptr<std::uint8_t[]> exact(
      new std::uint8_t[std::max<std::size_t>(1, png.size())]);
  std::copy(png.begin(), png.end(), exact.get());
  error.clear();
  const Status status = decoder.decode(exact.get(), png.size(), mode, out, error);
  if (status == Status::kCorrupt) {
    EXPECT_FALSE(error.empty());
  } else if (status == Status::kDecoded) {
    EXPECT_EQ(out.type(), mode == Mode::kDepth ? CV_16UC1 : CV_8UC3);
  }
  return status;
}

struct RealFile {
  std::string path;
  Mode mode;
};

std::vector<RealFile> realFiles() {
  const std::string dir = test::tumDir(kXyz);
  return {{dir + "/rgb/1305031102.311267.png", Mode::kColor},
          {dir + "/depth/1305031102.295279.png", Mode::kDepth}};
}

TEST(PngDecoder, TruncationAtEveryChunkBoundaryIsAnError) {
  for (const RealFile& file : realFiles()) {
    const Bytes png = readBytes(file.path);
    std::vector<std::size_t> cuts = {0, 1, 7, 8, 9};
    for (const Chunk& c : chunksOf(png))
      for (const std::size_t at :
           {c.offset, c.offset + 4, c.offset + 8, c.offset + 8 + c.length / 2,
            c.offset + 8 + c.length, c.offset + 11 + c.length})
        for (const std::size_t d : {0, 1})
          if (at + d < png.size()) cuts.push_back(at + d);
    PngDecoder decoder;
    cv::Mat out;
    for (const std::size_t cut : cuts) {
      std::string error;
      const Bytes truncated(png.begin(), png.begin() + static_cast<std::ptrdiff_t>(cut));
      ASSERT_EQ(decodeDamaged(decoder, truncated, file.mode, out, error), Status::kCorrupt)
          << file.path << " cut at " << cut;
      EXPECT_TRUE(out.empty());  // untouched by every failure
    }
    // After all those failures the same decoder decodes the whole file.
    std::string error;
    ASSERT_EQ(decoder.decode(png.data(), png.size(), file.mode, out, error), Status::kDecoded);
    EXPECT_TRUE(identical(out, openCv(png, file.mode)));
  }
}

TEST(PngDecoder, FlippedBytesGiveAnErrorOrAnImage) {
  std::mt19937 random(2024);
  for (const RealFile& file : realFiles()) {
    const Bytes png = readBytes(file.path);
    const std::vector<Chunk> chunks = chunksOf(png);
    PngDecoder decoder;
    cv::Mat out;
    std::size_t corrupt = 0;
    for (int trial = 0; trial < 150; ++trial) {
      Bytes damaged = png;
      // Half the trials aim at the first 64 bytes (signature, IHDR, the first chunk headers),
      // where a flip changes the most.
      for (int flips = 1 + int(random() % 3); flips > 0; --flips) {
        const std::size_t at = trial % 2 ? random() % 64 : random() % damaged.size();
        damaged[at] ^= static_cast<std::uint8_t>(1 + random() % 255);
      }
      std::string error;
      corrupt += decodeDamaged(decoder, damaged, file.mode, out, error) == Status::kCorrupt;
      // Again with the CRCs made right, so that the damage reaches the inflater and the
      // unfiltering instead of stopping at the CRC check.
      for (const Chunk& c : chunks)
        if (c.offset + 12 + c.length <= damaged.size()) fixCrc(damaged, c);
      decodeDamaged(decoder, damaged, file.mode, out, error);
    }
    EXPECT_GT(corrupt, 100u) << file.path;  // CRCs catch nearly every flip
  }
}

TEST(PngDecoder, DamageIsNamed) {
  const Bytes png = readBytes(realFiles()[1].path);
  const std::vector<Chunk> chunks = chunksOf(png);
  const Chunk& ihdr = chunks.front();
  const Chunk& idat = chunks[1];
  ASSERT_EQ(ihdr.type, "IHDR");
  ASSERT_EQ(idat.type, "IDAT");
  const auto reason = [](const Bytes& bytes) {
    PngDecoder decoder;
    cv::Mat out;
    std::string error;
    EXPECT_EQ(decoder.decode(bytes.data(), bytes.size(), Mode::kDepth, out, error),
              Status::kCorrupt);
    return error;
  };
  const auto contains = [](const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
  };

  EXPECT_EQ(reason(Bytes(png.begin(), png.begin() + 4)), "not a PNG file (bad signature)");
  Bytes damaged = png;
  damaged[idat.offset + 8] ^= 1;  // the zlib header
  EXPECT_EQ(reason(damaged), "bad CRC in the IDAT chunk at byte 33");
  fixCrc(damaged, idat);
  EXPECT_EQ(reason(damaged),
            "the compressed image data is corrupt (bad deflate stream or checksum)");

  Bytes cut(png.begin(), png.begin() + static_cast<std::ptrdiff_t>(idat.offset + 100));
  EXPECT_EQ(reason(cut), "truncated: the IDAT chunk at byte 33 holds " +
                             std::to_string(idat.length) + " bytes, 88 are left");
  cut.assign(png.begin(), png.end() - 12);  // no IEND
  EXPECT_EQ(reason(cut), "truncated: no IEND chunk");

  // The Adler-32 of the zlib stream: the last 4 bytes of the last IDAT.
  damaged = png;
  const Chunk& last_idat = chunks[chunks.size() - 2];
  ASSERT_EQ(last_idat.type, "IDAT");
  damaged[last_idat.offset + 8 + last_idat.length - 1] ^= 1;
  fixCrc(damaged, last_idat);
  EXPECT_EQ(reason(damaged),
            "the compressed image data is corrupt (bad deflate stream or checksum)");

  // An IHDR promising more rows than the data holds; one promising far more than any data of
  // this size could inflate to (refused before anything is allocated).
  damaged = png;
  damaged[ihdr.offset + 8 + 6] += 1;  // height 480 + 256
  fixCrc(damaged, ihdr);
  EXPECT_EQ(reason(damaged),
            "the image data inflates to fewer than the 942816 bytes of a 640x736 image");
  damaged[ihdr.offset + 8 + 4] = 0x80;  // height over 2^31
  fixCrc(damaged, ihdr);
  EXPECT_TRUE(contains(reason(damaged), "invalid image size 640x"));
  // 1000x983040: within every limit, and 2 GB of scanlines that 120 kB cannot inflate to.
  const Bytes huge = {0, 0, 0x03, 0xe8, 0, 0x0f, 0, 0};
  damaged = png;
  std::copy(huge.begin(), huge.end(),
            damaged.begin() + static_cast<std::ptrdiff_t>(ihdr.offset + 8));
  fixCrc(damaged, ihdr);
  EXPECT_TRUE(contains(reason(damaged), "bytes of image data cannot hold a 1000x983040 image"));

  // A filter type byte beyond Paeth.
  PngSpec spec;
  spec.bit_depth = 16;
  spec.colour_type = 0;
  spec.filter_of = [](std::size_t y) { return y == 5 ? 7 : 1; };
  EXPECT_EQ(reason(makePng(spec)), "row 5 has filter type 7 (0 to 4 are defined)");
}

// A zlib stream that inflates to more than the image: libpng decodes such a file with a
// warning, so the decoder leaves it to OpenCV rather than refusing what used to load.
TEST(PngDecoder, TooMuchImageDataIsLeftToOpenCv) {
  Bytes png = readBytes(realFiles()[1].path);
  const Chunk ihdr = chunksOf(png).front();
  png[ihdr.offset + 8 + 7] -= 1;  // 479 rows
  fixCrc(png, ihdr);
  expectLikeOpenCv(png, Mode::kDepth, Status::kUnsupported);
  EXPECT_EQ(openCv(png, Mode::kDepth).rows, 479);
}

TEST(PngDecoder, TumSequenceNamesTheDamagedFile) {
  const std::string dir = test::freshDir();
  fs::create_directories(dir + "/rgb");
  fs::create_directories(dir + "/depth");
  {
    std::ofstream(dir + "/rgb.txt") << "# colour\n1.0 rgb/a.png\n";
    std::ofstream(dir + "/depth.txt") << "# depth\n1.0 depth/a.png\n";
  }
  writeBytes(dir + "/rgb/a.png", readBytes(realFiles()[0].path));
  Bytes png = readBytes(realFiles()[1].path);
  png[45] ^= 1;  // in the first IDAT's data
  writeBytes(dir + "/depth/a.png", png);
  TumSequence sequence(dir);
  Frame frame;
  std::string error;
  ASSERT_FALSE(sequence.load(0, frame, error));
  EXPECT_EQ(error, dir + "/depth.txt:2: " + dir +
                       "/depth/a.png: cannot decode image (bad CRC in the IDAT chunk at byte 33)");
  EXPECT_EQ(sequence.failureReason(), "depth image: cannot decode image");
}

}  // namespace
}  // namespace rgbdmap
