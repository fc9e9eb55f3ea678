#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/drivers/kinect_v1_model.hpp"

namespace rgbdmap {

// Writes frames as a fakenect dump: what libfreenect's `fakenect` replays as a Kinect v1
// (FAKENECT_PATH=DIR). The folder holds INDEX.txt, one file name per line in playback order;
// each name is "<type>-<seconds>-<device stamp>-<anything>", which fakenect parses for the
// type ('d' depth, 'r' colour) and the time it paces playback by. Depth files are "P5 640 480
// 65535\n" and the raw 11-bit disparity (KinectV1Model, unregistered to the IR camera's view) as
// little-endian 16-bit words; colour files "P6 640 480 255\n" and RGB bytes; accelerometer files
// ('a', before the depth of a frame that knows its up) libfreenect's raw tilt state.
class FakenectDump {
 public:
  // Creates `dir` (refused when it already holds an INDEX.txt). Throws InputError naming it.
  explicit FakenectDump(const std::string& dir);
  // Adds one frame (depth in metres, registered to colour; colour BGR), 640x480. Throws
  // InputError when a file cannot be written or the frame is not 640x480.
  void add(const Frame& frame);
  std::uint64_t frames() const { return frames_; }

 private:
  void writeFile(const std::string& name, const std::string& header, const void* data,
                 std::size_t bytes);

  const std::string dir_;
  const KinectV1Model model_;
  std::ofstream index_;
  std::uint64_t frames_ = 0;
  std::vector<std::uint16_t> colour_raw_;
  std::vector<std::uint16_t> ir_raw_;
};

}  // namespace rgbdmap
