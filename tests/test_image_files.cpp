// Image files without OpenCV's codecs linked in: PNGs written by PngEncoder read back exactly by
// OpenCV (and so by any PNG reader), other formats through the module loaded on demand.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "rgbdmap/base/image_file.hpp"
#include "rgbdmap/base/opencv_codecs.hpp"
#include "rgbdmap/base/png_encoder.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

cv::Mat randomImage(int rows, int cols, int type, unsigned seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, image.depth() == CV_8U ? 256 : 65536);
  return image;
}

// Smooth content with edges, where every filter gets chosen somewhere.
cv::Mat gradientImage(int rows, int cols, int type) {
  cv::Mat image(rows, cols, type);
  const int channels = image.channels();
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) {
      for (int c = 0; c < channels; ++c) {
        const int value = (u * (c + 1) + v * 3 + (u > cols / 2 ? 90 : 0)) % 256;
        if (image.depth() == CV_8U)
          image.ptr<std::uint8_t>(v)[u * channels + c] = static_cast<std::uint8_t>(value);
        else
          image.ptr<std::uint16_t>(v)[u * channels + c] =
              static_cast<std::uint16_t>(value * 257 + v);
      }
    }
  }
  return image;
}

void expectSame(const cv::Mat& expected, const cv::Mat& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  ASSERT_EQ(expected.type(), actual.type());
  EXPECT_EQ(cv::norm(expected, actual, cv::NORM_INF), 0.0);
}

TEST(PngEncoder, EveryImageTypeReadsBackExactlyWithOpenCv) {
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3}) {
    for (const int level : {0, 1, 9}) {
      for (const cv::Mat& image : {randomImage(37, 53, type, 7), gradientImage(64, 80, type)}) {
        PngEncoder encoder(level);
        std::vector<std::uint8_t> png;
        std::string error;
        ASSERT_TRUE(encoder.encode(image, png, error)) << error;
        const cv::Mat back = cv::imdecode(png, cv::IMREAD_UNCHANGED);
        SCOPED_TRACE("type " + std::to_string(type) + " level " + std::to_string(level));
        expectSame(image, back);
      }
    }
  }
}

TEST(PngEncoder, RecordedFramesRoundTripAndCompressLikeOpenCv) {
  const std::string folder = test::tumDir(test::kXyz);
  std::size_t ours = 0, theirs = 0;
  PngEncoder encoder(1);
  int images = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder + "/depth")) {
    if (images++ == 4) break;
    for (const std::string& path :
         {entry.path().string(), folder + "/rgb/" + entry.path().filename().string()}) {
      if (!std::filesystem::exists(path)) continue;
      const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
      std::vector<std::uint8_t> png, reference;
      std::string error;
      ASSERT_TRUE(encoder.encode(image, png, error)) << error;
      expectSame(image, cv::imdecode(png, cv::IMREAD_UNCHANGED));
      cv::imencode(".png", image, reference, {cv::IMWRITE_PNG_COMPRESSION, 1});
      ours += png.size();
      theirs += reference.size();
    }
  }
  ASSERT_GT(theirs, 0u);
  // Same filters and a comparable deflate: files about as small as libpng's at the same level.
  EXPECT_LT(static_cast<double>(ours), 1.15 * static_cast<double>(theirs));
}

TEST(PngEncoder, RefusesWhatPngCannotHold) {
  PngEncoder encoder;
  std::vector<std::uint8_t> png;
  std::string error;
  EXPECT_FALSE(encoder.encode(cv::Mat(4, 4, CV_32FC1, cv::Scalar(1.0f)), png, error));
  EXPECT_NE(error.find("PNG holds"), std::string::npos) << error;
  EXPECT_FALSE(encoder.encode(cv::Mat(), png, error));
}

TEST(ImageFiles, PngAndOtherFormatsAreWrittenAndReadBack) {
  const std::string dir = test::freshDir();
  const cv::Mat colour = gradientImage(48, 64, CV_8UC3);
  std::string error;
  ASSERT_TRUE(writeImageFile(dir + "/a.png", colour, error)) << error;
  expectSame(colour, cv::imread(dir + "/a.png", cv::IMREAD_UNCHANGED));
  // Through the module: JPEG (lossy: close, not equal) and TIFF (exact).
  ASSERT_TRUE(writeImageFile(dir + "/a.jpg", colour, error)) << error;
  const cv::Mat jpeg = cv::imread(dir + "/a.jpg");
  ASSERT_EQ(jpeg.size(), colour.size());
  EXPECT_LT(cv::norm(jpeg, colour, cv::NORM_L1) / static_cast<double>(colour.total() * 3), 8.0);
  const cv::Mat depth = gradientImage(48, 64, CV_16UC1);
  ASSERT_TRUE(writeImageFile(dir + "/d.tiff", depth, error)) << error;
  expectSame(depth, cv::imread(dir + "/d.tiff", cv::IMREAD_UNCHANGED));

  const OpenCvCodecs* codecs = OpenCvCodecs::get(error);
  ASSERT_NE(codecs, nullptr) << error;
  EXPECT_TRUE(codecs->canRead(dir + "/a.jpg"));
  std::vector<std::uint8_t> bytes;
  cv::imencode(".jpg", colour, bytes);
  cv::Mat decoded;
  ASSERT_TRUE(codecs->decode(bytes.data(), bytes.size(), cv::IMREAD_COLOR, decoded, error));
  expectSame(jpeg, decoded);
}

TEST(ImageFiles, AFailedWriteNamesThePath) {
  std::string error;
  EXPECT_FALSE(writeImageFile("/nonexistent-dir/a.png", cv::Mat(4, 4, CV_8UC3), error));
  EXPECT_NE(error.find("/nonexistent-dir/a.png"), std::string::npos) << error;
  EXPECT_FALSE(writeImageFile("/nonexistent-dir/a.jpg", cv::Mat(4, 4, CV_8UC3), error));
  EXPECT_NE(error.find("/nonexistent-dir/a.jpg"), std::string::npos) << error;
}

// The program maps TUM recordings (PNG) without OpenCV's codecs library: with it, GDAL and
// about 130 other libraries would take some 40 MB of every run's memory.
TEST(ImageFiles, TheProgramDoesNotLinkOpenCvsCodecs) {
  const std::string core =
      (std::filesystem::path(test::binary()).parent_path() / "rgbdmap-core").string();
  ASSERT_TRUE(std::filesystem::exists(core)) << core;
  std::string libraries;
  ASSERT_EQ(test::run("ldd " + core, &libraries), 0) << libraries;
  EXPECT_NE(libraries.find("libopencv_core"), std::string::npos) << libraries;
  EXPECT_EQ(libraries.find("libopencv_imgcodecs"), std::string::npos);
  EXPECT_EQ(libraries.find("libgdal"), std::string::npos);
}

}  // namespace
}  // namespace rgbdmap
