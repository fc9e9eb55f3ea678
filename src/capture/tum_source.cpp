#include "rgbdmap/capture/tum_source.hpp"

#include <spdlog/spdlog.h>

#include <thread>

namespace rgbdmap {

TumSource::TumSource(const std::string& folder, const TumSequence::Options& options,
                     const CameraIntrinsics& camera, double rate)
    : sequence_(folder, options), camera_(camera), rate_(rate) {}

std::string TumSource::describe() const {
  return "tum:" + sequence_.folder() + " (" + std::to_string(sequence_.size()) + " frames, " +
         (sequence_.hasGroundtruth()
              ? std::to_string(sequence_.size() - sequence_.framesWithoutPose()) +
                    " with ground truth"
              : std::string("no ground truth")) +
         ")";
}

ReadStatus TumSource::read(Frame& frame) {
  if (next_ >= sequence_.size()) return ReadStatus::kEnd;
  const std::size_t i = next_++;
  if (rate_ > 0) {
    if (i == 0) start_ = std::chrono::steady_clock::now();
    const double offset = (sequence_[i].rgb_time - sequence_[0].rgb_time) / rate_;
    std::this_thread::sleep_until(start_ +
                                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(offset)));
  }
  std::string error;
  if (!sequence_.load(i, frame, error)) {
    spdlog::warn("skipping frame {}: {}", i, error);
    reasons_.add(sequence_.failureReason(), error);
    ++skipped_;
    return ReadStatus::kSkipped;
  }
  if (frame.depth.cols != camera_.width || frame.depth.rows != camera_.height) {
    error = sequence_[i].depth_path + ": image is " + std::to_string(frame.depth.cols) + "x" +
            std::to_string(frame.depth.rows) + " but the camera is configured as " +
            std::to_string(camera_.width) + "x" + std::to_string(camera_.height);
    spdlog::warn("skipping frame {}: {}", i, error);
    reasons_.add("image size differs from camera.width x camera.height", error);
    ++skipped_;
    return ReadStatus::kSkipped;
  }
  return ReadStatus::kFrame;
}

}  // namespace rgbdmap
