#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace rgbdmap {

// One non-comment line of a whitespace-separated text file, with its 1-based line number.
struct TextLine {
  std::size_t number = 0;
  std::vector<std::string> fields;
};

// Reads the data lines of a TUM-style text file ('#' starts a comment line; blank lines are
// skipped). Throws InputError if the file cannot be opened.
std::vector<TextLine> readTextLines(const std::string& path);

// Parses a finite double; throws InputError "path:line: <what> '<text>' is not a number".
double parseNumber(const std::string& text, const std::string& path, std::size_t line,
                   const char* what);

}  // namespace rgbdmap
