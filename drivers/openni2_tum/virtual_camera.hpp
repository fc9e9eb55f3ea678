#pragma once

#include <OniCTypes.h>

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "tum_device_uri.hpp"

namespace rgbdmap::openni2_tum {

// A TUM folder presented as a camera: what outlives the OpenNI2 device objects opened on it
// (a host closes and reopens, an unplug and replug makes OpenNI2 create a new one): the
// associated sequence, the playback position and whether the camera is plugged in.
// Thread-safe; at any time only the device opened since the last replug plays from it.
class VirtualCamera {
 public:
  // One associated colour/depth pair in playback order.
  struct Shot {
    std::size_t entry = 0;  // index of the pair in the sequence
    int frame_index = 0;    // OpenNI2 frame index: 1 + pairs played before it (loops included)
    std::uint64_t color_timestamp_us = 0;  // rgb.txt stamp in microseconds (+ whole loops)
    std::uint64_t depth_timestamp_us = 0;  // depth.txt stamp in microseconds (+ whole loops)
    double pace_time = 0.0;  // colour stamp in seconds (+ whole loops): when it is due
  };

  // Reads and associates the folder's lists; throws InputError naming what is wrong.
  explicit VirtualCamera(const TumDeviceUri& uri);

  const TumDeviceUri& uri() const { return uri_; }
  const OniDeviceInfo& info() const { return info_; }
  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  const std::string& folder() const { return sequence_.folder(); }
  std::size_t size() const { return sequence_.size(); }  // associated pairs in the folder

  // Starts over at the end (the URI's loop option until set).
  bool looping() const;
  void setLooping(bool looping);
  // Plays `frame_index` next (1 = the first pair); false when it is out of the sequence.
  bool seek(int frame_index);

  // Changes at every unplug: a device remembers the generation it was opened in.
  std::uint64_t generation() const;
  bool plugged() const;
  void replug();

  // The next pair for a device of `generation`; nothing once the camera was unplugged since,
  // or at the end of the sequence when it does not loop.
  std::optional<Shot> peek(std::uint64_t generation) const;
  // Decodes `shot` (depth in metres, colour BGR) and moves past it, also when the images
  // cannot be read: then returns false with a message naming the file and list line.
  bool take(const Shot& shot, Frame& frame, std::string& error);
  // Counts a pair delivered by a device of `generation`; returns true when that reaches
  // disconnect_after, which unplugs the camera.
  bool countDelivered(std::uint64_t generation);

 private:
  Shot shotAt(std::uint64_t position) const;

  const TumDeviceUri uri_;
  TumSequence sequence_;  // load() reuses buffers: guarded by mutex_ as well
  CameraIntrinsics intrinsics_;
  OniDeviceInfo info_{};
  std::uint64_t loop_period_us_ = 0;  // a loop's timestamp shift

  mutable std::mutex mutex_;
  std::uint64_t position_ = 0;  // pairs played so far, loops included
  std::uint64_t generation_ = 0;
  bool plugged_ = true;
  std::size_t delivered_since_plug_ = 0;
  bool looping_;
};

}  // namespace rgbdmap::openni2_tum
