#pragma once

#include <chrono>
#include <string>

#include "rgbdmap/capture/frame_source.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"

namespace rgbdmap {

// A TUM sequence replayed as a camera. With rate > 0 frames are released at the recorded
// timing scaled by the rate (the queue then drops what the mapper cannot take in time, as with
// a live camera); with rate 0 they come as fast as the mapper takes them, losslessly.
class TumSource : public FrameSource {
 public:
  TumSource(const std::string& folder, const TumSequence::Options& options,
            const CameraIntrinsics& camera, double rate);

  ReadStatus read(Frame& frame) override;
  CameraIntrinsics intrinsics() const override { return camera_; }
  bool isLive() const override { return rate_ > 0; }
  bool providesPoses() const override { return sequence_.hasGroundtruth(); }
  std::string describe() const override;
  std::uint64_t skipped() const override { return skipped_; }
  std::vector<SkipReasons::Entry> skipReasons() const override { return reasons_.entries(); }
  const TumSequence& sequence() const { return sequence_; }

 private:
  TumSequence sequence_;
  CameraIntrinsics camera_;
  double rate_;
  std::size_t next_ = 0;
  std::uint64_t skipped_ = 0;
  SkipReasons reasons_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace rgbdmap
