#pragma once

#include <stdexcept>
#include <string>

namespace rgbdmap {

// Bad input that stops the run: the message names the file (and line) or device and says what
// is wrong. main() prints it and exits non-zero after saving whatever was already mapped.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "file:line: what" in one place so every message has the same shape.
inline std::string where(const std::string& file, std::size_t line) {
  return file + ":" + std::to_string(line);
}

}  // namespace rgbdmap
