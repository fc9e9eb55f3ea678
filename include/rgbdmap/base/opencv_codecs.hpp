#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

namespace rgbdmap {

// OpenCV's image codecs (JPEG, TIFF, BMP, ... every format but the PNGs the project codes
// itself), reached through a module loaded the first time such a file is met. Linking
// libopencv_imgcodecs would load GDAL, poppler, xerces and some 130 other libraries into every
// run: about 40 MB of resident memory, a sixth of a long replay's peak, for files TUM
// recordings do not have.
//
// The module (rgbdmap-opencv-codecs.so, built from plugins/) is looked for in
// $RGBDMAP_CODECS_MODULE (a path), next to the executable, in ../lib/rgbdmap from it, and in the
// build tree. Thread-safe.
class OpenCvCodecs {
 public:
  // The loaded module, or nullptr with `error` naming where it was looked for.
  static const OpenCvCodecs* get(std::string& error);

  // cv::imdecode(bytes, flags) into `out`; false with `error` when no codec reads the data.
  bool decode(const std::uint8_t* data, std::size_t size, int flags, cv::Mat& out,
              std::string& error) const;
  // cv::imwrite(path, image, params); false with `error` when it cannot.
  bool write(const std::string& path, const cv::Mat& image, const std::vector<int>& params,
             std::string& error) const;
  // cv::haveImageReader(path).
  bool canRead(const std::string& path) const;

  // The module's exported functions (C names; C++ types: built with the same compiler and
  // OpenCV as the core).
  using DecodeFunction = bool (*)(const std::uint8_t*, std::size_t, int, cv::Mat*, std::string*);
  using WriteFunction = bool (*)(const char*, const cv::Mat*, const int*, std::size_t,
                                 std::string*);
  using CanReadFunction = bool (*)(const char*);

 private:
  DecodeFunction decode_ = nullptr;
  WriteFunction write_ = nullptr;
  CanReadFunction can_read_ = nullptr;
};

}  // namespace rgbdmap
