#pragma once

#include <Driver/OniDriverAPI.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "device_announcer.hpp"
#include "driver_log.hpp"
#include "virtual_camera.hpp"

namespace rgbdmap::openni2_tum {

// The OpenNI2 driver: turns `tum:` URIs into VirtualCameras and opens devices on them.
// Folders listed in RGBDMAP_TUM_DEVICES (absolute paths separated by ':', each optionally
// followed by ?options as in a URI) are announced at initialization, so enumeration lists
// them; any other folder becomes a device when a program opens "tum:<folder>".
class TumDriver : public oni::driver::DriverBase {
 public:
  static constexpr const char* kDevicesVariable = "RGBDMAP_TUM_DEVICES";

  explicit TumDriver(OniDriverServices* services);
  ~TumDriver() override;

  OniStatus initialize(oni::driver::DeviceConnectedCallback connected,
                       oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback state_changed,
                       void* cookie) override;
  OniStatus tryDevice(const char* uri) override;
  oni::driver::DeviceBase* deviceOpen(const char* uri, const char* mode) override;
  void deviceClose(oni::driver::DeviceBase* device) override;
  void shutdown() override;
  void* enableFrameSync(oni::driver::StreamBase** streams, int count) override;
  void disableFrameSync(void* group) override;

 private:
  // Creates (or finds) the camera for `uri` and announces it; on failure returns why.
  std::shared_ptr<VirtualCamera> connect(const std::string& uri, std::string& error);
  // Announces the unplug now and, with reconnect_after_ms, the replug later.
  void unplug(const std::shared_ptr<VirtualCamera>& camera);

  DriverLog log_;
  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<VirtualCamera>> cameras_;  // by URI
  DeviceAnnouncer announcer_;
};

}  // namespace rgbdmap::openni2_tum
