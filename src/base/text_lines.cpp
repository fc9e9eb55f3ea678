#include "rgbdmap/base/text_lines.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {

std::vector<TextLine> readTextLines(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open file");
  std::vector<TextLine> lines;
  std::string text;
  std::size_t number = 0;
  while (std::getline(in, text)) {
    ++number;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const auto first = text.find_first_not_of(" \t");
    if (first == std::string::npos || text[first] == '#') continue;
    TextLine line{number, {}};
    std::istringstream fields(text);
    for (std::string f; fields >> f;) line.fields.push_back(f);
    lines.push_back(std::move(line));
  }
  if (in.bad()) throw InputError(path + ": read error");
  return lines;
}

double parseNumber(const std::string& text, const std::string& path, std::size_t line,
                   const char* what) {
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || errno == ERANGE)
    throw InputError(where(path, line) + ": " + what + " '" + text + "' is not a number");
  if (!std::isfinite(value))
    throw InputError(where(path, line) + ": " + what + " is " + text + " (not finite)");
  return value;
}

}  // namespace rgbdmap
