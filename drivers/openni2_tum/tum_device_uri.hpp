#pragma once

#include <chrono>
#include <cstddef>
#include <optional>
#include <string>

namespace rgbdmap::openni2_tum {

// A device URI of the plugin: `tum:/path/to/folder[?option=value[&option=value]...]`.
//   disconnect_after=N     stop after N delivered frames and report the device unplugged
//   reconnect_after_ms=M   then report it plugged in again M ms later (needs disconnect_after)
//   loop=0|1               start over at the end of the sequence (default 0: frames stop)
struct TumDeviceUri {
  static constexpr const char* kScheme = "tum:";

  std::string text;                  // the URI as given: OpenNI2 identifies the device by it
  std::string folder;                // the folder as written in the URI
  std::size_t disconnect_after = 0;  // 0: never
  std::optional<std::chrono::milliseconds> reconnect_after;
  bool loop = false;

  static bool hasScheme(const std::string& uri);
  // Throws std::invalid_argument naming the URI and the part that is wrong.
  static TumDeviceUri parse(const std::string& uri);
};

}  // namespace rgbdmap::openni2_tum
