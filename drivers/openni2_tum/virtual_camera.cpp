#include "virtual_camera.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>

#include "camera_presets.hpp"

namespace rgbdmap::openni2_tum {
namespace {

std::uint64_t microseconds(double seconds) {
  return static_cast<std::uint64_t>(std::llround(seconds * 1e6));
}

void copyText(char (&target)[ONI_MAX_STR], const std::string& text) {
  std::strncpy(target, text.c_str(), ONI_MAX_STR - 1);
  target[ONI_MAX_STR - 1] = '\0';
}

// The folder as an absolute path, fixed when the device is created: frames are read later on
// another thread, after the host (or OpenNI2 itself, while it loads drivers) may have changed
// the working directory.
std::string absoluteFolder(const std::string& folder) {
  std::error_code ignored;
  const std::filesystem::path absolute = std::filesystem::absolute(folder, ignored);
  return absolute.empty() ? folder : absolute.string();
}

}  // namespace

VirtualCamera::VirtualCamera(const TumDeviceUri& uri)
    : uri_(uri),
      sequence_(absoluteFolder(uri.folder)),
      intrinsics_(intrinsicsForFolder(sequence_.folder())),
      looping_(uri.loop) {
  copyText(info_.uri, uri_.text);
  copyText(info_.vendor, "TUM RGB-D");
  copyText(info_.name, std::filesystem::path(sequence_.folder()).filename().string());
  // A loop starts one mean frame interval after the last frame, so stamps keep increasing.
  const double first = sequence_[0].rgb_time;
  const double last = sequence_[sequence_.size() - 1].rgb_time;
  const double interval = sequence_.size() > 1 ? (last - first) / (sequence_.size() - 1) : 1 / 30.0;
  loop_period_us_ = microseconds(last - first + interval);
}

bool VirtualCamera::looping() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return looping_;
}

void VirtualCamera::setLooping(bool looping) {
  std::lock_guard<std::mutex> lock(mutex_);
  looping_ = looping;
}

bool VirtualCamera::seek(int frame_index) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (frame_index < 1 || static_cast<std::size_t>(frame_index) > sequence_.size()) return false;
  position_ = static_cast<std::uint64_t>(frame_index - 1);
  return true;
}

std::uint64_t VirtualCamera::generation() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return generation_;
}

bool VirtualCamera::plugged() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return plugged_;
}

void VirtualCamera::replug() {
  std::lock_guard<std::mutex> lock(mutex_);
  plugged_ = true;
  delivered_since_plug_ = 0;
}

VirtualCamera::Shot VirtualCamera::shotAt(std::uint64_t position) const {
  const std::uint64_t loop = position / sequence_.size();
  const TumEntry& entry = sequence_[position % sequence_.size()];
  Shot shot;
  shot.entry = position % sequence_.size();
  shot.frame_index = static_cast<int>(position + 1);
  shot.color_timestamp_us = microseconds(entry.rgb_time) + loop * loop_period_us_;
  shot.depth_timestamp_us = microseconds(entry.depth_time) + loop * loop_period_us_;
  shot.pace_time = entry.rgb_time + static_cast<double>(loop * loop_period_us_) * 1e-6;
  return shot;
}

std::optional<VirtualCamera::Shot> VirtualCamera::peek(std::uint64_t generation) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!plugged_ || generation != generation_) return std::nullopt;
  if (!looping_ && position_ >= sequence_.size()) return std::nullopt;
  return shotAt(position_);
}

bool VirtualCamera::take(const Shot& shot, Frame& frame, std::string& error) {
  std::lock_guard<std::mutex> lock(mutex_);
  position_ = static_cast<std::uint64_t>(shot.frame_index);
  frame.index = static_cast<std::uint64_t>(shot.frame_index - 1);
  return sequence_.load(shot.entry, frame, error);
}

bool VirtualCamera::countDelivered(std::uint64_t generation) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!plugged_ || generation != generation_) return false;
  ++delivered_since_plug_;
  if (uri_.disconnect_after == 0 || delivered_since_plug_ < uri_.disconnect_after) return false;
  plugged_ = false;
  ++generation_;
  return true;
}

}  // namespace rgbdmap::openni2_tum
