#include "rgbdmap/runtime/exit_code.hpp"

#include <spdlog/spdlog.h>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {

int exitCodeFor(const std::exception& error) {
  return dynamic_cast<const InputError*>(&error) ? 2 : 1;
}

int runGuarded(const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return exitCodeFor(e);
  }
}

}  // namespace rgbdmap
