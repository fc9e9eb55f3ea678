#pragma once

#include <memory>
#include <optional>
#include <string>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/skip_reasons.hpp"

namespace rgbdmap {

// What a read from a camera produced.
enum class ReadStatus {
  kFrame,    // the frame was filled
  kSkipped,  // this capture was unusable (message already logged); the stream goes on
  kEnd,      // a recording or sequence has no more frames
  kTimeout,  // a live camera delivered nothing within the timeout (maybe unplugged)
};

// A camera: a live device, a recording or a dataset replayed as if it were a camera.
// Sources are driven from the capture thread only.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // Fills `frame` in place (its images are reused between calls).
  virtual ReadStatus read(Frame& frame) = 0;
  virtual CameraIntrinsics intrinsics() const = 0;
  // True when frames come from a live sensor: the queue drops instead of blocking.
  virtual bool isLive() const = 0;
  // Whether frames carry poses of their own (ground truth of a dataset).
  virtual bool providesPoses() const = 0;
  // Human-readable description for logs ("tum:/path (fr1, 798 frames)").
  virtual std::string describe() const = 0;
  // Frames the source itself had to skip (missing/corrupt images, no ground truth, ...).
  virtual std::uint64_t skipped() const { return 0; }
  // Those skipped frames by reason, for the end-of-run summary (empty: no reasons kept).
  virtual std::vector<SkipReasons::Entry> skipReasons() const { return {}; }
  // Whether a kTimeout may be followed by a reconnect (a live camera that was unplugged).
  virtual bool canReconnect() const { return false; }
  // One attempt to get the same camera back after kTimeout; may block for up to about a second.
  // Returns true when frames can be read again.
  virtual bool reconnect() { return false; }
};

}  // namespace rgbdmap
