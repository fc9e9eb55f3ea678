#pragma once

#include <Driver/OniDriverAPI.h>

#include <mutex>
#include <vector>

namespace rgbdmap::openni2_freenect {

// OpenNI2 driver for the Kinect v1 on libfreenect (Debian's libfreenect0.5, or its fakenect
// replay library). Each Kinect libfreenect counts when OpenNI2 initializes is announced as
// "freenect:<index>" (Microsoft Kinect v1, USB 045e:02ae).
class FreenectDriver : public oni::driver::DriverBase {
 public:
  explicit FreenectDriver(OniDriverServices* services) : DriverBase(services) {}

  OniStatus initialize(oni::driver::DeviceConnectedCallback connected,
                       oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback state_changed,
                       void* cookie) override;
  oni::driver::DeviceBase* deviceOpen(const char* uri, const char* mode) override;
  void deviceClose(oni::driver::DeviceBase* device) override;
  OniStatus tryDevice(const char* uri) override;
  void shutdown() override {}

 private:
  // The index of a known URI, or -1.
  int indexOf(const char* uri) const;

  std::vector<OniDeviceInfo> devices_;  // announced at initialize, index = libfreenect's
};

}  // namespace rgbdmap::openni2_freenect
