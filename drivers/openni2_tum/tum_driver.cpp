#include "tum_driver.hpp"

#include <chrono>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <utility>
#include <vector>

#include "tum_device.hpp"
#include "tum_device_uri.hpp"

namespace rgbdmap::openni2_tum {
namespace {

// Closing a device waits for a replug due within this (longer ones are announced by the timer
// alone, and can still meet a host's shutdown), and for announcements late by up to the slack.
constexpr std::chrono::seconds kReplugWaitedForOnClose{5};
constexpr std::chrono::seconds kAnnouncementSlack{5};

// OpenNI2 only needs a non-null handle for a frame sync group: the devices give the depth and
// colour frames of a pair the same index, which is all its SyncedStreamsFrameHolder matches.
struct FrameSyncGroup {
  std::vector<oni::driver::StreamBase*> streams;
};

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::istringstream in(text);
  for (std::string part; std::getline(in, part, separator);)
    if (!part.empty()) parts.push_back(part);
  return parts;
}

}  // namespace

TumDriver::TumDriver(OniDriverServices* services) : DriverBase(services), log_(getServices()) {}

TumDriver::~TumDriver() { shutdown(); }

OniStatus TumDriver::initialize(oni::driver::DeviceConnectedCallback connected,
                                oni::driver::DeviceDisconnectedCallback disconnected,
                                oni::driver::DeviceStateChangedCallback state_changed,
                                void* cookie) {
  const OniStatus status = DriverBase::initialize(connected, disconnected, state_changed, cookie);
  if (status != ONI_STATUS_OK) return status;
  const char* listed = std::getenv(kDevicesVariable);
  if (listed == nullptr) return ONI_STATUS_OK;
  for (const std::string& entry : split(listed, ':')) {
    // OpenNI2 calls this with the working directory set to its driver folder.
    if (entry.front() != '/') {
      log_.warning(std::string(kDevicesVariable) + ": '" + entry +
                   "' is not an absolute path; not announced");
      continue;
    }
    std::string error;
    if (!connect(TumDeviceUri::kScheme + entry, error))
      log_.warning(std::string(kDevicesVariable) + ": " + error + "; not announced");
  }
  return ONI_STATUS_OK;
}

std::shared_ptr<VirtualCamera> TumDriver::connect(const std::string& uri, std::string& error) {
  std::shared_ptr<VirtualCamera> camera;
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto known = cameras_.find(uri);
    if (known != cameras_.end()) {
      // OpenNI2 asks only for devices it does not list: this one is unplugged, or its replug
      // is being announced right now (then OpenNI2 lists it once that announcement is out).
      if (known->second->plugged()) return known->second;
      const TumDeviceUri& options = known->second->uri();
      error = uri + " is unplugged (disconnect_after=" + std::to_string(options.disconnect_after) +
              ")" +
              (options.reconnect_after
                   ? "; it comes back " + std::to_string(options.reconnect_after->count()) +
                         " ms after it went"
                   : std::string());
      return nullptr;
    }
    camera = std::make_shared<VirtualCamera>(TumDeviceUri::parse(uri));
    cameras_.emplace(uri, camera);
  } catch (const std::exception& e) {
    error = "cannot open " + uri + ": " + e.what();
    return nullptr;
  }
  log_.info("device " + uri + " connected (" + camera->folder() + ")");
  deviceConnected(&camera->info());  // outside the lock: the host's listeners run inside
  return camera;
}

OniStatus TumDriver::tryDevice(const char* uri) {
  if (uri == nullptr || !TumDeviceUri::hasScheme(uri)) return ONI_STATUS_ERROR;  // not ours
  std::string error;
  if (connect(uri, error)) return ONI_STATUS_OK;
  log_.error(error);
  getServices().errorLoggerAppend("TumDevice: %s", error.c_str());
  return ONI_STATUS_ERROR;
}

oni::driver::DeviceBase* TumDriver::deviceOpen(const char* uri, const char* /*mode*/) {
  std::shared_ptr<VirtualCamera> camera;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto known = cameras_.find(uri == nullptr ? "" : uri);
    if (known != cameras_.end()) camera = known->second;
  }
  if (!camera || !camera->plugged()) return nullptr;
  try {
    return new TumDevice(camera, log_, [this](const std::shared_ptr<VirtualCamera>& unplugged) {
      unplug(unplugged);
    });
  } catch (const std::exception& e) {
    log_.error(std::string("cannot open ") + uri + ": " + e.what());
    getServices().errorLoggerAppend("TumDevice: cannot open %s: %s", uri, e.what());
    return nullptr;
  }
}

void TumDriver::deviceClose(oni::driver::DeviceBase* device) {
  // OpenNI2 holds its device lock while it destroys the drivers, and announcing takes that lock:
  // an announcement that starts while a host shuts down can neither finish nor be waited for (a
  // recorder that stopped at the frame that unplugged the camera hung there). So the unplug
  // (scheduled by the playback thread this joins) and a replug due soon go out before the
  // close returns; a host that closes its devices before shutting down never meets one. The
  // slack bounds the wait of a host that shuts down with the device open, closing it under the
  // lock.
  delete static_cast<TumDevice*>(device);
  announcer_.finishDue(DeviceAnnouncer::Clock::now() + kReplugWaitedForOnClose, kAnnouncementSlack);
}

void TumDriver::unplug(const std::shared_ptr<VirtualCamera>& camera) {
  const DeviceAnnouncer::Clock::time_point now = DeviceAnnouncer::Clock::now();
  announcer_.schedule(now, [this, camera] {
    log_.info(std::string("device ") + camera->info().uri + " disconnected");
    deviceDisconnected(&camera->info());
  });
  if (!camera->uri().reconnect_after) return;
  announcer_.schedule(now + *camera->uri().reconnect_after, [this, camera] {
    camera->replug();
    log_.info(std::string("device ") + camera->info().uri + " connected again");
    deviceConnected(&camera->info());
  });
}

void TumDriver::shutdown() {
  announcer_.stop();
  std::lock_guard<std::mutex> lock(mutex_);
  cameras_.clear();
}

void* TumDriver::enableFrameSync(oni::driver::StreamBase** streams, int count) {
  if (streams == nullptr || count <= 0) return nullptr;
  return new FrameSyncGroup{std::vector<oni::driver::StreamBase*>(streams, streams + count)};
}

void TumDriver::disableFrameSync(void* group) { delete static_cast<FrameSyncGroup*>(group); }

}  // namespace rgbdmap::openni2_tum

// OniDriverAPI.h's ONI_EXPORT_DRIVER allocates with XnLib's macros, which Debian does not
// install with the OpenNI2 headers.
#define XN_NEW(type, ...) new type(__VA_ARGS__)
#define XN_DELETE(p) delete (p)
ONI_EXPORT_DRIVER(rgbdmap::openni2_tum::TumDriver)
