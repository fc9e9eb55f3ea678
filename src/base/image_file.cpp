#include "rgbdmap/base/image_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "rgbdmap/base/opencv_codecs.hpp"
#include "rgbdmap/base/png_encoder.hpp"

namespace rgbdmap {

bool writeImageFile(const std::string& path, const cv::Mat& image, std::string& error,
                    int png_compression) {
  std::string extension = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".png" && PngEncoder::supports(image)) {
    PngEncoder encoder(png_compression);
    std::vector<std::uint8_t> bytes;
    if (!encoder.encode(image, bytes, error)) {
      error = path + ": cannot write image (" + error + ")";
      return false;
    }
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (out)
      out.write(reinterpret_cast<const char*>(bytes.data()),
                static_cast<std::streamsize>(bytes.size()));
    if (out) out.close();
    if (!out) {
      error = path + ": cannot write image (" + std::strerror(errno) + ")";
      return false;
    }
    return true;
  }
  const OpenCvCodecs* codecs = OpenCvCodecs::get(error);
  if (codecs == nullptr) {
    error = path + ": cannot write image: " + error;
    return false;
  }
  std::string reason;
  if (!codecs->write(path, image, {cv::IMWRITE_PNG_COMPRESSION, png_compression}, reason)) {
    error = path + ": cannot write image (" + reason + ")";
    return false;
  }
  return true;
}

}  // namespace rgbdmap
