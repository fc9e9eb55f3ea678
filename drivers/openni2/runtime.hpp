#pragma once

#include <memory>
#include <string>

namespace rgbdmap::openni2 {

// Initialises OpenNI2 for its first user and shuts it down after its last one.
// Every object that holds OpenNI2 state keeps a reference, so none outlives
// OpenNI::shutdown() (a known crash). Nothing static holds a reference:
// shutting down from an exit handler, after the drivers' own statics are gone,
// makes Debian's PS1080 driver free memory twice.
class Runtime {
 public:
  // Throws InputError when OpenNI2 cannot start.
  static std::shared_ptr<Runtime> acquire();
  Runtime(const Runtime&) = delete;
  Runtime& operator=(const Runtime&) = delete;

 private:
  Runtime() = default;
};

// OpenNI2's extended error without its tabs and trailing newlines ("no details" when empty).
std::string lastError();

}  // namespace rgbdmap::openni2

namespace rgbdmap::openni2 {

// Keeps `object` alive until the process ends. Debian's OniFile driver crashes in its player
// thread about one time in ten when a recording is closed (or OpenNI2 shut down after one);
// played recordings are kept open here, and so OpenNI2 is never shut down after one. The list is
// never freed (reachable, so leak checkers do not count it).
void keepUntilExit(std::shared_ptr<void> object);

}  // namespace rgbdmap::openni2
