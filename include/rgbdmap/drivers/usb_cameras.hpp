#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rgbdmap {

// A Kinect-class camera (or a part of one) seen on the USB bus, and whether this user can use it.
struct UsbCamera {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string model;      // "Microsoft Kinect v1 (camera)", "PrimeSense / ASUS Xtion", ...
  bool is_camera = true;  // false for the Kinect v1's motor and audio parts (listed for info)
  int bus = 0;
  int address = 0;
  std::string port_path;  // Linux style "1-1.4": bus, then the hub ports down to the device
  int open_error = 0;     // 0 when libusb_open worked, else the libusb error code
  std::string problem;    // why OpenNI2 may not get at it ("" when nothing is known to be wrong)
  std::string advice;     // what to do about `problem`

  std::string ids() const;       // "045e:02ae"
  std::string describe() const;  // one line: model, ids, bus/port, access
};

// What a look at the USB bus found.
struct UsbScan {
  bool bus_readable = false;
  std::string bus_error;           // why the bus could not be read (when !bus_readable)
  std::size_t devices_seen = 0;    // all USB devices, cameras or not
  std::vector<UsbCamera> cameras;  // Kinect v1, PrimeSense/ASUS Xtion and Orbbec devices

  bool anyCamera() const;  // an entry with is_camera
};

// Lists the known RGB-D cameras on the USB bus (libusb-1.0) and tries to open each one, so that a
// missing permission (LIBUSB_ERROR_ACCESS) or a missing OpenNI2 driver can be named.
UsbScan scanUsbCameras();

// The udev rule shipped with rgbdmap and the commands that install it.
std::string udevRulePath();
std::string udevInstallCommands();

// The folder libOpenNI2 loads its drivers from (beside the library it was loaded from).
std::string openni2DriverDirectory();

}  // namespace rgbdmap
