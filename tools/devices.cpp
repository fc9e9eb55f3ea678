// `rgbdmap devices`: which RGB-D cameras are on the USB bus, whether this user may open them, and
// what OpenNI2 can open; says what to do when a camera is there but cannot be used.
#include <cstdio>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/drivers/openni2_source.hpp"
#include "rgbdmap/drivers/usb_cameras.hpp"
#include "rgbdmap/tools/commands.hpp"

namespace rgbdmap {
namespace {

int listDevices() {
  const UsbScan scan = scanUsbCameras();
  if (!scan.bus_readable) {
    std::printf("USB: the bus could not be read (%s): no camera found\n", scan.bus_error.c_str());
  } else if (scan.cameras.empty()) {
    std::printf(
        "USB: no camera found among %zu USB devices (looked for Microsoft Kinect v1 "
        "045e:02ae, PrimeSense/ASUS Xtion 1d27:06xx, Orbbec 2bc5:*)%s\n",
        scan.devices_seen,
        scan.devices_seen == 0 ? "; no USB device is visible at all (in a container, "
                                 "pass /dev/bus/usb in)"
                               : "");
  } else {
    std::printf("USB: %zu RGB-D camera device(s) among %zu USB devices:\n", scan.cameras.size(),
                scan.devices_seen);
    for (const UsbCamera& camera : scan.cameras) {
      std::printf("  %s\n", camera.describe().c_str());
      if (!camera.problem.empty()) std::printf("    problem: %s\n", camera.problem.c_str());
      if (!camera.advice.empty()) std::printf("    to do: %s\n", camera.advice.c_str());
    }
    if (!scan.anyCamera())
      std::printf(
          "  no camera part: a Kinect v1 shows its camera (045e:02ae) only with its own "
          "power supply plugged in\n");
  }

  std::printf("OpenNI2 (drivers in %s): ", openni2DriverDirectory().c_str());
  try {
    const std::vector<std::string> devices = listOpenNI2Devices();
    if (devices.empty())
      std::printf("no device it can open\n");
    else
      std::printf("%zu device(s) it can open:\n", devices.size());
    for (const std::string& device : devices) std::printf("  openni2:%s\n", device.c_str());
  } catch (const InputError& e) {
    std::printf("%s\n", e.what());
  }
  std::printf("udev rule for camera access without root: %s\n", udevInstallCommands().c_str());
  return 0;
}

}  // namespace

void addDevicesCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "devices", "list RGB-D cameras on the USB bus, whether you may open them, and what to do");
  cmd->callback([&selected] { selected = [] { return listDevices(); }; });
}

}  // namespace rgbdmap
