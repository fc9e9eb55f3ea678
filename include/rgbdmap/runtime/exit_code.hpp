#pragma once

#include <exception>
#include <functional>

namespace rgbdmap {

// The exit code of a program that an error ended, the same for every front door and tool:
// 2 for bad input or configuration (InputError: its message names the file and line, key,
// parameter or device), 1 for anything else.
int exitCodeFor(const std::exception& error);

// Runs `body` and returns its exit code; an exception it throws is logged and gives
// exitCodeFor's code.
int runGuarded(const std::function<int()>& body);

}  // namespace rgbdmap
