#pragma once

#include <string>

namespace rgbdmap {

// Whether a window can be opened: an X display that accepts a connection and offers OpenGL
// (GLX). When not, `why` says what is missing.
bool displayAvailable(std::string& why);

}  // namespace rgbdmap
