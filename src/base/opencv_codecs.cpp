#include "rgbdmap/base/opencv_codecs.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>

namespace rgbdmap {
namespace {

constexpr const char* kModule = "rgbdmap-opencv-codecs.so";

std::vector<std::string> candidates() {
  std::vector<std::string> paths;
  if (const char* path = std::getenv("RGBDMAP_CODECS_MODULE"); path && *path) paths.push_back(path);
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    paths.push_back((exe.parent_path() / kModule).string());
    paths.push_back((exe.parent_path().parent_path() / "lib" / "rgbdmap" / kModule).string());
  }
#ifdef RGBDMAP_BUILD_DIR
  paths.push_back(std::string(RGBDMAP_BUILD_DIR) + "/" + kModule);
#endif
  return paths;
}

}  // namespace

const OpenCvCodecs* OpenCvCodecs::get(std::string& error) {
  static std::once_flag once;
  static OpenCvCodecs codecs;
  static bool loaded = false;
  static std::string why;
  std::call_once(once, [] {
    std::string tried;
    for (const std::string& path : candidates()) {
      if (!std::filesystem::exists(path)) {
        tried += (tried.empty() ? "" : ", ") + path;
        continue;
      }
      // Never unloaded: cv::Mat buffers it allocates may outlive any one call.
      void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (module == nullptr) {
        const char* reason = dlerror();
        why = path + ": cannot load (" + (reason ? reason : "unknown reason") + ")";
        return;
      }
      codecs.decode_ = reinterpret_cast<DecodeFunction>(dlsym(module, "rgbdmap_codecs_decode"));
      codecs.write_ = reinterpret_cast<WriteFunction>(dlsym(module, "rgbdmap_codecs_write"));
      codecs.can_read_ =
          reinterpret_cast<CanReadFunction>(dlsym(module, "rgbdmap_codecs_can_read"));
      if (!codecs.decode_ || !codecs.write_ || !codecs.can_read_) {
        why = path + ": not rgbdmap's OpenCV codecs module (a function is missing)";
        return;
      }
      loaded = true;
      return;
    }
    why = std::string("OpenCV image codecs module ") + kModule + " not found (looked for " + tried +
          "; reinstall rgbdmap)";
  });
  if (!loaded) error = why;
  return loaded ? &codecs : nullptr;
}

bool OpenCvCodecs::decode(const std::uint8_t* data, std::size_t size, int flags, cv::Mat& out,
                          std::string& error) const {
  return decode_(data, size, flags, &out, &error);
}

bool OpenCvCodecs::write(const std::string& path, const cv::Mat& image,
                         const std::vector<int>& params, std::string& error) const {
  return write_(path.c_str(), &image, params.data(), params.size(), &error);
}

bool OpenCvCodecs::canRead(const std::string& path) const { return can_read_(path.c_str()); }

}  // namespace rgbdmap
