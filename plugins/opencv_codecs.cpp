// rgbdmap-opencv-codecs.so: OpenCV's image codecs behind three C entry points, loaded by
// rgbdmap::OpenCvCodecs only when a file needs them (include/rgbdmap/base/opencv_codecs.hpp says
// why they are not linked into the program).
#include "rgbdmap/base/opencv_codecs.hpp"

#include <opencv2/imgcodecs.hpp>

extern "C" {

bool rgbdmap_codecs_decode(const std::uint8_t* data, std::size_t size, int flags, cv::Mat* out,
                           std::string* error) {
  try {
    const cv::Mat bytes(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data));
    cv::imdecode(bytes, flags, out);
  } catch (const cv::Exception& e) {
    *error = e.err;
    return false;
  }
  return true;
}

bool rgbdmap_codecs_write(const char* path, const cv::Mat* image, const int* params,
                          std::size_t count, std::string* error) {
  try {
    if (cv::imwrite(path, *image, std::vector<int>(params, params + count))) return true;
    *error = "no codec wrote it";
  } catch (const cv::Exception& e) {
    *error = e.err;
  }
  return false;
}

bool rgbdmap_codecs_can_read(const char* path) {
  try {
    return cv::haveImageReader(path);
  } catch (const cv::Exception&) {
    return false;
  }
}

}  // extern "C"
