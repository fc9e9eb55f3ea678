#pragma once

#include <memory>
#include <string>
#include <vector>

#include "rgbdmap/capture/camera_options.hpp"
#include "rgbdmap/capture/frame_source.hpp"

namespace rgbdmap {

// A camera through OpenNI2: "" opens the first device, a path ending in ".oni" plays that
// recording (losslessly, at replay.rate timing unless it is 0), anything else is a device URI
// (including URIs of driver plugins, such as "tum:/path/to/folder").
// Depth comes as metres (from DEPTH_100_UM or DEPTH_1_MM), colour as BGR, both registered and
// synchronised where the device supports it; stamps are the device clock in seconds.
// Throws InputError naming the file or device when it cannot be opened; with no camera attached
// the message says what is on the USB bus and why it could not be used.
// `rate`: replay.rate.
std::unique_ptr<FrameSource> openOpenNI2Source(const std::string& uri_or_file,
                                               const CameraOptions& camera, double rate);

// The devices OpenNI2 can open right now, one "URI (vendor name, USB vvvv:pppp)" each.
std::vector<std::string> listOpenNI2Devices();

// Which camera model `uri` ("" = the first device OpenNI2 lists) is, from its USB id or name:
// "xtion" for PrimeSense / ASUS Xtion / Carmine (USB 1d27:*), "kinect_v1" for a Kinect v1 and
// any other camera, "" when OpenNI2 lists no such device (or cannot start).
std::string openNI2CameraModel(const std::string& uri);

}  // namespace rgbdmap
