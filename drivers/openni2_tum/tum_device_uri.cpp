#include "tum_device_uri.hpp"

#include <OniCTypes.h>

#include <charconv>
#include <cstring>
#include <stdexcept>

namespace rgbdmap::openni2_tum {
namespace {

// A whole non-negative decimal number, or nothing.
std::optional<unsigned long long> parseCount(const std::string& text) {
  unsigned long long value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

}  // namespace

bool TumDeviceUri::hasScheme(const std::string& uri) {
  return uri.compare(0, std::strlen(kScheme), kScheme) == 0;
}

TumDeviceUri TumDeviceUri::parse(const std::string& uri) {
  const auto fail = [&uri](const std::string& what) {
    throw std::invalid_argument("device URI '" + uri + "': " + what);
  };
  if (!hasScheme(uri)) fail(std::string("does not start with '") + kScheme + "'");
  // OniDeviceInfo keeps the URI in a fixed char array, and OpenNI2 finds devices by it.
  if (uri.size() >= ONI_MAX_STR)
    fail("longer than " + std::to_string(ONI_MAX_STR - 1) + " characters");

  TumDeviceUri parsed;
  parsed.text = uri;
  const std::size_t query = uri.find('?');
  parsed.folder = uri.substr(std::strlen(kScheme), query - std::strlen(kScheme));
  if (parsed.folder.empty()) fail("no folder after 'tum:'");

  std::string rest = query == std::string::npos ? "" : uri.substr(query + 1);
  while (!rest.empty()) {
    const std::size_t amp = rest.find('&');
    const std::string option = rest.substr(0, amp);
    rest = amp == std::string::npos ? "" : rest.substr(amp + 1);
    const std::size_t eq = option.find('=');
    if (eq == std::string::npos) fail("option '" + option + "' has no '=value'");
    const std::string key = option.substr(0, eq);
    const std::string value = option.substr(eq + 1);
    const std::optional<unsigned long long> number = parseCount(value);
    if (key == "disconnect_after") {
      if (!number || *number == 0) fail("disconnect_after must be a whole number >= 1");
      parsed.disconnect_after = static_cast<std::size_t>(*number);
    } else if (key == "reconnect_after_ms") {
      if (!number) fail("reconnect_after_ms must be a whole number of milliseconds");
      parsed.reconnect_after = std::chrono::milliseconds(*number);
    } else if (key == "loop") {
      if (value != "0" && value != "1") fail("loop must be 0 or 1");
      parsed.loop = value == "1";
    } else {
      fail("unknown option '" + key + "' (known: disconnect_after, reconnect_after_ms, loop)");
    }
  }
  if (parsed.reconnect_after && parsed.disconnect_after == 0)
    fail("reconnect_after_ms needs disconnect_after");
  return parsed;
}

}  // namespace rgbdmap::openni2_tum
