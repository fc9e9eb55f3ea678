#include "rgbdmap/drivers/usb_cameras.hpp"

#include <OniCAPI.h>
#include <dlfcn.h>
#include <libusb.h>

#include <cstdio>
#include <filesystem>
#include <memory>

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

constexpr std::uint16_t kMicrosoft = 0x045e;
constexpr std::uint16_t kPrimeSense = 0x1d27;
constexpr std::uint16_t kOrbbec = 0x2bc5;

// What a vendor/product pair is, or "" when it is not a camera rgbdmap knows.
std::string modelOf(std::uint16_t vendor, std::uint16_t product, bool& is_camera) {
  is_camera = true;
  if (vendor == kMicrosoft) {
    if (product == 0x02ae) return "Microsoft Kinect v1 (camera)";
    if (product == 0x02bf) return "Microsoft Kinect for Windows v1 (camera)";
    is_camera = false;
    if (product == 0x02b0 || product == 0x02c2) return "Microsoft Kinect v1 (motor)";
    if (product == 0x02ad || product == 0x02be) return "Microsoft Kinect v1 (audio)";
    return "";
  }
  if (vendor == kPrimeSense && (product & 0xff00) == 0x0600) return "PrimeSense / ASUS Xtion";
  if (vendor == kOrbbec) return "Orbbec";
  return "";
}

// Whether a driver whose file name starts with `stem` is in OpenNI2's driver folder.
bool openni2HasDriver(const std::string& stem) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(openni2DriverDirectory(), ec))
    if (entry.path().filename().string().rfind(stem, 0) == 0) return true;
  return false;
}

void diagnose(UsbCamera& camera) {
  if (camera.open_error == LIBUSB_ERROR_ACCESS) {
    camera.problem = "no permission to open it (LIBUSB_ERROR_ACCESS)";
    camera.advice =
        "install the udev rule, then unplug and replug the camera: " + udevInstallCommands();
    return;
  }
  if (camera.open_error == LIBUSB_ERROR_BUSY) {
    camera.problem = "it is in use (LIBUSB_ERROR_BUSY)";
    camera.advice =
        "close the other program that uses it (or unload the gspca_kinect kernel "
        "module for a Kinect v1: sudo modprobe -r gspca_kinect)";
    return;
  }
  if (camera.open_error != 0) {
    camera.problem =
        std::string("libusb cannot open it (") + libusb_error_name(camera.open_error) + ")";
    camera.advice = "unplug and replug it; check `dmesg` for USB errors";
    return;
  }
  if (!camera.is_camera) return;
  if (camera.vendor_id == kMicrosoft && !openni2HasDriver("libFreenectDriver") &&
      !openni2HasDriver("libKinectV1Device")) {
    camera.problem = "OpenNI2 has no driver for a Kinect v1 (" + openni2DriverDirectory() +
                     " has neither rgbdmap's libKinectV1Device nor libfreenect's "
                     "libFreenectDriver)";
    camera.advice =
        "rgbdmap builds its Kinect v1 driver when libfreenect-dev is installed (sudo apt-get "
        "install libfreenect-dev, then rebuild); other OpenNI2 programs need it copied as " +
        openni2DriverDirectory() + "/libKinectV1Device.so.0";
  } else if (camera.vendor_id == kOrbbec && !openni2HasDriver("libOrbbec")) {
    camera.problem = "OpenNI2 has no driver for Orbbec cameras (" + openni2DriverDirectory() +
                     " has no libOrbbec)";
    camera.advice =
        "install libOrbbec.so from Orbbec's OpenNI2 SDK into that folder as "
        "libOrbbec.so.0";
  } else if (camera.vendor_id == kPrimeSense) {
    camera.advice =
        "if OpenNI2 still cannot stream from it: use a USB 2 port (Xtions fail on "
        "many USB 3 ports) and no other streaming device on the same controller "
        "(a PrimeSense camera reserves most of a USB 2 bus)";
  }
}

}  // namespace

std::string UsbCamera::ids() const {
  char text[16];
  std::snprintf(text, sizeof text, "%04x:%04x", vendor_id, product_id);
  return text;
}

std::string UsbCamera::describe() const {
  std::string line = model + " " + ids() + " on bus " + std::to_string(bus) + " port " + port_path +
                     " (address " + std::to_string(address) + "): ";
  line += open_error == 0
              ? "this user can open it"
              : std::string("this user cannot open it: ") + libusb_error_name(open_error);
  return line;
}

bool UsbScan::anyCamera() const {
  for (const UsbCamera& c : cameras)
    if (c.is_camera) return true;
  return false;
}

UsbScan scanUsbCameras() {
  UsbScan scan;
  libusb_context* raw_context = nullptr;
  if (const int rc = libusb_init(&raw_context); rc != 0) {
    scan.bus_error = std::string("libusb_init failed: ") + libusb_error_name(rc);
    return scan;
  }
  const std::unique_ptr<libusb_context, void (*)(libusb_context*)> context(raw_context,
                                                                           libusb_exit);
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(context.get(), &list);
  if (count < 0) {
    scan.bus_error =
        std::string("cannot list USB devices: ") + libusb_error_name(static_cast<int>(count));
    return scan;
  }
  scan.bus_readable = true;
  scan.devices_seen = static_cast<std::size_t>(count);
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device* device = list[i];
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(device, &descriptor) != 0) continue;
    UsbCamera camera;
    camera.model = modelOf(descriptor.idVendor, descriptor.idProduct, camera.is_camera);
    if (camera.model.empty()) continue;
    camera.vendor_id = descriptor.idVendor;
    camera.product_id = descriptor.idProduct;
    camera.bus = libusb_get_bus_number(device);
    camera.address = libusb_get_device_address(device);
    std::uint8_t ports[8];
    const int depth = libusb_get_port_numbers(device, ports, sizeof ports);
    camera.port_path = std::to_string(camera.bus) + "-";
    for (int p = 0; p < depth; ++p) camera.port_path += (p ? "." : "") + std::to_string(ports[p]);
    libusb_device_handle* handle = nullptr;
    camera.open_error = libusb_open(device, &handle);
    if (handle) libusb_close(handle);
    diagnose(camera);
    scan.cameras.push_back(camera);
  }
  libusb_free_device_list(list, 1);
  return scan;
}

std::string udevRulePath() {
  // The rule ships in the source tree beside the config presets' folder.
  const fs::path rule =
      fs::path(RGBDMAP_CONFIG_DIR).parent_path() / "drivers/udev/99-rgbdmap-cameras.rules";
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(rule, ec);
  return ec ? rule.string() : canonical.string();
}

std::string udevInstallCommands() {
  return "sudo cp " + udevRulePath() +
         " /etc/udev/rules.d/ && sudo udevadm control --reload-rules && sudo udevadm trigger";
}

std::string openni2DriverDirectory() {
  // libOpenNI2 looks for OpenNI2/Drivers beside the file it was loaded from.
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&oniInitialize), &info) && info.dli_fname)
    return (fs::path(info.dli_fname).parent_path() / "OpenNI2/Drivers").string();
  return "/usr/lib/x86_64-linux-gnu/OpenNI2/Drivers";
}

}  // namespace rgbdmap
