#pragma once

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace rgbdmap {

// File and file-name tests the layers share. A path that cannot be inspected (missing, or a
// folder on the way unreadable) is neither a file nor a folder: callers report it as missing.
inline bool isFile(const std::string& path) {
  std::error_code ignored;
  return std::filesystem::is_regular_file(path, ignored);
}
inline bool isDirectory(const std::string& path) {
  std::error_code ignored;
  return std::filesystem::is_directory(path, ignored);
}
inline bool pathExists(const std::string& path) {
  std::error_code ignored;
  return std::filesystem::exists(path, ignored);
}

// Whether `text` ends with `suffix`, byte for byte (e.g. a file name and its extension).
inline bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The same ignoring ASCII case, for extensions that cameras and tools write in capitals too.
inline bool endsWithIgnoringCase(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         std::equal(suffix.rbegin(), suffix.rend(), text.rbegin(), [](char a, char b) {
           return std::tolower(static_cast<unsigned char>(a)) ==
                  std::tolower(static_cast<unsigned char>(b));
         });
}

}  // namespace rgbdmap
