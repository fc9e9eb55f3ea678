#pragma once

#include <string>

namespace oni::driver {
class DriverServices;
}

namespace rgbdmap::openni2_tum {

// Where the plugin's messages go: OpenNI2's log (shown when the host program turned it on)
// and, for warnings and errors, stderr too: a skipped frame or a folder that cannot be read
// must be visible even in programs that never enable OpenNI2 logging.
class DriverLog {
 public:
  explicit DriverLog(oni::driver::DriverServices& services) : services_(services) {}

  void info(const std::string& message);
  void warning(const std::string& message);
  void error(const std::string& message);

 private:
  void write(int severity, const std::string& message);

  oni::driver::DriverServices& services_;
};

}  // namespace rgbdmap::openni2_tum
