#pragma once
// Shared by the libFuzzer targets: the parsers under test read files, so each input is written
// to a private scratch folder first (in /dev/shm when there is one: no disk wear).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace rgbdmap::fuzz {

inline std::string scratchDir() {
  static const std::string dir = [] {
    const std::string base = std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
    const std::string d = base + "/rgbdmap-fuzz-" + std::to_string(::getpid());
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

inline void writeFile(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Splits the input at 0x01 bytes into at most `parts` pieces (fewer when it has fewer).
inline std::vector<std::string> split(const std::uint8_t* data, std::size_t size,
                                      std::size_t parts) {
  std::vector<std::string> out(1);
  for (std::size_t i = 0; i < size; ++i) {
    if (data[i] == 0x01 && out.size() < parts)
      out.emplace_back();
    else
      out.back().push_back(static_cast<char>(data[i]));
  }
  return out;
}

}  // namespace rgbdmap::fuzz
