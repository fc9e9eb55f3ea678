#include "driver_log.hpp"

#include <Driver/OniDriverAPI.h>

#include <cstdio>

namespace rgbdmap::openni2_tum {
namespace {

// XnLogSeverity values (XnLog.h is not installed with the OpenNI2 headers).
constexpr int kSeverityInfo = 1;
constexpr int kSeverityWarning = 2;
constexpr int kSeverityError = 3;
constexpr const char* kLogMask = "TumDevice";

}  // namespace

void DriverLog::info(const std::string& message) { write(kSeverityInfo, message); }
void DriverLog::warning(const std::string& message) { write(kSeverityWarning, message); }
void DriverLog::error(const std::string& message) { write(kSeverityError, message); }

void DriverLog::write(int severity, const std::string& message) {
  services_.log(severity, __FILE__, __LINE__, kLogMask, message.c_str());
  if (severity >= kSeverityWarning) std::fprintf(stderr, "%s: %s\n", kLogMask, message.c_str());
}

}  // namespace rgbdmap::openni2_tum
