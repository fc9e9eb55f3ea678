#include "freenect_driver.hpp"

#include <libfreenect.h>

#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "kinect_device.hpp"

namespace rgbdmap::openni2_freenect {
namespace {

void copyText(char* target, std::size_t size, const std::string& text) {
  std::snprintf(target, size, "%s", text.c_str());
}

}  // namespace

OniStatus FreenectDriver::initialize(oni::driver::DeviceConnectedCallback connected,
                                     oni::driver::DeviceDisconnectedCallback disconnected,
                                     oni::driver::DeviceStateChangedCallback state_changed,
                                     void* cookie) {
  DriverBase::initialize(connected, disconnected, state_changed, cookie);
  freenect_context* context = nullptr;
  if (freenect_init(&context, nullptr) < 0) {
    getServices().errorLoggerAppend("KinectV1Device: libfreenect cannot start");
    return ONI_STATUS_OK;  // no Kinect, but OpenNI2 and its other drivers go on
  }
  freenect_select_subdevices(context, FREENECT_DEVICE_CAMERA);
  const int count = freenect_num_devices(context);
  freenect_shutdown(context);
  for (int i = 0; i < count; ++i) {
    OniDeviceInfo info{};
    copyText(info.uri, sizeof info.uri, "freenect:" + std::to_string(i));
    copyText(info.vendor, sizeof info.vendor, "Microsoft");
    copyText(info.name, sizeof info.name, "Kinect v1");
    info.usbVendorId = 0x045e;
    info.usbProductId = 0x02ae;
    devices_.push_back(info);
  }
  for (const OniDeviceInfo& info : devices_) deviceConnected(&info);
  return ONI_STATUS_OK;
}

int FreenectDriver::indexOf(const char* uri) const {
  if (uri == nullptr) return -1;
  for (std::size_t i = 0; i < devices_.size(); ++i)
    if (std::strcmp(devices_[i].uri, uri) == 0) return static_cast<int>(i);
  return -1;
}

OniStatus FreenectDriver::tryDevice(const char* uri) {
  return indexOf(uri) >= 0 ? ONI_STATUS_OK : ONI_STATUS_ERROR;
}

oni::driver::DeviceBase* FreenectDriver::deviceOpen(const char* uri, const char* /*mode*/) {
  const int index = indexOf(uri);
  if (index < 0) return nullptr;
  const OniDeviceInfo* info = &devices_[static_cast<std::size_t>(index)];
  try {
    return new KinectDevice(index, [this, info] { deviceDisconnected(info); });
  } catch (const std::exception& e) {  // nothing may cross into OpenNI2's C code
    getServices().errorLoggerAppend("KinectV1Device: %s: %s", uri, e.what());
    return nullptr;
  }
}

void FreenectDriver::deviceClose(oni::driver::DeviceBase* device) {
  delete static_cast<KinectDevice*>(device);
}

}  // namespace rgbdmap::openni2_freenect

// OniDriverAPI.h's ONI_EXPORT_DRIVER allocates with XnLib's macros, which Debian does not
// install with the OpenNI2 headers.
#define XN_NEW(type, ...) new type(__VA_ARGS__)
#define XN_DELETE(p) delete (p)
ONI_EXPORT_DRIVER(rgbdmap::openni2_freenect::FreenectDriver)
