#pragma once

#include <OpenNI.h>

#include <atomic>
#include <string>

namespace rgbdmap::openni2 {

// Reports when OpenNI2 announces that the opened device went away (unplugged),
// so a read can stop waiting at once instead of after the full timeout.
class DisconnectWatch : public openni::OpenNI::DeviceDisconnectedListener {
 public:
  explicit DisconnectWatch(std::string uri) : uri_(std::move(uri)) {}
  void onDeviceDisconnected(const openni::DeviceInfo* info) override {
    if (info && uri_ == info->getUri()) disconnected_.store(true);
  }
  bool disconnected() const { return disconnected_.load(); }

 private:
  const std::string uri_;
  std::atomic<bool> disconnected_{false};
};

}  // namespace rgbdmap::openni2
