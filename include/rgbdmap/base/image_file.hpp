#pragma once

#include <opencv2/core/mat.hpp>
#include <string>

namespace rgbdmap {

// Writes `image` to `path` as cv::imwrite would: a .png name whose image type PNG holds is written
// by PngEncoder (`png_compression` 0-9, as IMWRITE_PNG_COMPRESSION), anything else through
// OpenCV's codecs module. False with `error` ("path: reason") when it cannot; a failed write may
// leave a partial file, so callers that must not write to a temporary name and rename.
bool writeImageFile(const std::string& path, const cv::Mat& image, std::string& error,
                    int png_compression = 1);

}  // namespace rgbdmap
