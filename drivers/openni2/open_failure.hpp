#pragma once

#include <string>

namespace rgbdmap::openni2 {

// Why OpenNI2 could not open `uri` ("" = the first device, a path ending in ".oni" = a
// recording), for the user: a missing or unplayable recording, or a device that failed to open.
// With `diagnose`, "" is explained from what the USB bus shows and a URI is followed by the
// devices OpenNI2 lists. Call right after the failed open (it reads OpenNI2's extended error).
std::string openFailure(const std::string& uri, bool diagnose);

}  // namespace rgbdmap::openni2
