#pragma once

#include <OniCTypes.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <type_traits>

namespace rgbdmap {

// OpenNI2 hands a driver plugin (openni2_tum, openni2_freenect) property values as (pointer, size
// in bytes); these check the size against the property's type instead of trusting the caller.
template <typename T>
OniStatus readProperty(const void* data, int size, T& value) {
  static_assert(std::is_trivially_copyable_v<T>);
  if (data == nullptr || size != static_cast<int>(sizeof(T))) return ONI_STATUS_BAD_PARAMETER;
  std::memcpy(&value, data, sizeof(T));
  return ONI_STATUS_OK;
}

template <typename T>
OniStatus writeProperty(void* data, int* size, const T& value) {
  static_assert(std::is_trivially_copyable_v<T>);
  if (data == nullptr || size == nullptr || *size != static_cast<int>(sizeof(T)))
    return ONI_STATUS_BAD_PARAMETER;
  std::memcpy(data, &value, sizeof(T));
  return ONI_STATUS_OK;
}

// A string property: as much as fits, always NUL-terminated; *size becomes the bytes written.
inline OniStatus writeProperty(void* data, int* size, const std::string& value) {
  if (data == nullptr || size == nullptr || *size <= 0) return ONI_STATUS_BAD_PARAMETER;
  const std::size_t n = std::min(value.size(), static_cast<std::size_t>(*size - 1));
  std::memcpy(data, value.data(), n);
  static_cast<char*>(data)[n] = '\0';
  *size = static_cast<int>(n + 1);
  return ONI_STATUS_OK;
}

}  // namespace rgbdmap
