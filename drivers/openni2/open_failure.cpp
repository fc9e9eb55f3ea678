#include "open_failure.hpp"

#include <OpenNI.h>

#include "rgbdmap/base/file_names.hpp"
#include "rgbdmap/drivers/usb_cameras.hpp"
#include "runtime.hpp"

namespace rgbdmap::openni2 {
namespace {

// The reason `rgbdmap --source openni2` found nothing, from what the USB bus
// shows.
std::string noCameraMessage(const std::string& openni_error) {
  std::string message =
      "--source openni2: no camera found: OpenNI2 opened no device (" + openni_error + ")";
  const UsbScan scan = scanUsbCameras();
  if (!scan.bus_readable)
    return message + "; the USB bus could not be read either (" + scan.bus_error + ")";
  if (!scan.anyCamera()) {
    message +=
        "; the USB bus shows no Kinect v1 (045e:02ae), PrimeSense/ASUS Xtion (1d27:06xx) or Orbbec "
        "(2bc5:*) camera";
    message += scan.devices_seen == 0
                   ? std::string(" and no USB device at all (in a container, pass /dev/bus/usb in)")
                   : " among its " + std::to_string(scan.devices_seen) + " devices";
    if (!scan.cameras.empty())
      message +=
          "; only the motor/audio parts of a Kinect v1 are there: its camera needs the Kinect's "
          "own power supply plugged in";
    return message +
           ". Plug a camera in, or replay a recording: --source openni2:FILE.oni or --source "
           "tum:DIR (`rgbdmap devices` lists cameras and access)";
  }
  message += "; on the USB bus:";
  for (const UsbCamera& camera : scan.cameras) {
    message += "\n  " + camera.describe();
    if (!camera.problem.empty()) message += "; " + camera.problem;
    if (!camera.advice.empty()) message += "; " + camera.advice;
  }
  return message;
}

}  // namespace

std::string openFailure(const std::string& uri, bool diagnose) {
  const std::string error = lastError();
  if (endsWith(uri, ".oni")) {
    if (!pathExists(uri)) return "openni2:" + uri + ": no such recording file";
    return "openni2:" + uri + ": OpenNI2 cannot play this file as a recording (" +
           (error == "no details" ? std::string("corrupt or truncated?") : error) + ")";
  }
  if (uri.empty()) {
    return diagnose ? noCameraMessage(error) : "openni2: no camera found (" + error + ")";
  }
  std::string message = "openni2:" + uri + ": OpenNI2 cannot open this device (" + error + ")";
  if (!diagnose) return message;
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  message += "; devices OpenNI2 lists: ";
  if (devices.getSize() == 0) message += "none";
  for (int i = 0; i < devices.getSize(); ++i)
    message += std::string(i ? ", " : "") + devices[i].getUri();
  return message;
}

}  // namespace rgbdmap::openni2
