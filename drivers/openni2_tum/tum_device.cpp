#include "tum_device.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <utility>

#include "color_stream.hpp"
#include "depth_stream.hpp"
#include "driver_log.hpp"
#include "rgbdmap/drivers/oni_property.hpp"

namespace rgbdmap::openni2_tum {
namespace {

using Clock = std::chrono::steady_clock;

// The first pair of a run comes one frame interval after the first stream starts, like a
// camera's first frame, so a second stream started right after the first still gets it.
constexpr std::chrono::microseconds kFirstFrameDelay(1000000 / kTumFps);

// In manual mode, how long a poke that came during a delivery waits for the host to poke again
// before it is taken as the request for the next pair (see play()).
constexpr std::chrono::seconds kUnansweredPokeWait(1);

OniVersion driverVersion() {
  OniVersion version;
  version.major = TUM_DEVICE_VERSION_MAJOR;
  version.minor = TUM_DEVICE_VERSION_MINOR;
  version.maintenance = TUM_DEVICE_VERSION_PATCH;
  version.build = 0;
  return version;
}

}  // namespace

TumDevice::TumDevice(std::shared_ptr<VirtualCamera> camera, DriverLog& log,
                     UnplugHandler on_unplugged)
    : camera_(std::move(camera)),
      generation_(camera_->generation()),
      log_(log),
      on_unplugged_(std::move(on_unplugged)),
      depth_modes_(DepthStream::videoModes()),
      color_modes_(ColorStream::videoModes()) {
  sensors_[0] = {ONI_SENSOR_DEPTH, static_cast<int>(depth_modes_.size()), depth_modes_.data()};
  sensors_[1] = {ONI_SENSOR_COLOR, static_cast<int>(color_modes_.size()), color_modes_.data()};
  // Opening a recording plays it from the start (a camera that unplugs goes on where it was).
  if (playsLikeRecording()) camera_->seek(1);
  player_ = std::thread([this] { play(); });
}

TumDevice::~TumDevice() {
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    closing_ = true;
    state_changed_.notify_all();
  }
  player_.join();
}

OniStatus TumDevice::getSensorInfoList(OniSensorInfo** sensors, int* count) {
  if (sensors == nullptr || count == nullptr) return ONI_STATUS_BAD_PARAMETER;
  *sensors = sensors_;
  *count = 2;
  return ONI_STATUS_OK;
}

oni::driver::StreamBase* TumDevice::createStream(OniSensorType type) {
  try {
    StreamHost& host = *this;
    std::unique_ptr<TumStream> stream;
    if (type == ONI_SENSOR_DEPTH) {
      stream = std::make_unique<DepthStream>(camera_->intrinsics(), host, log_);
    } else if (type == ONI_SENSOR_COLOR) {
      stream = std::make_unique<ColorStream>(camera_->intrinsics(), host, log_);
    } else {
      return nullptr;  // a TUM folder has no infrared images
    }
    std::lock_guard<std::mutex> lock(streams_mutex_);
    streams_.push_back(std::move(stream));
    {
      std::lock_guard<std::mutex> state_lock(state_mutex_);
      ++created_streams_;
    }
    return streams_.back().get();
  } catch (const std::exception& e) {  // nothing may cross into OpenNI2's C code
    log_.error(std::string("cannot create a stream: ") + e.what());
    return nullptr;
  }
}

void TumDevice::destroyStream(oni::driver::StreamBase* stream) {
  if (stream == nullptr) return;
  stream->stop();  // OpenNI2 stops streams first; a stream still running must not be counted
  std::lock_guard<std::mutex> lock(streams_mutex_);
  {
    std::lock_guard<std::mutex> state_lock(state_mutex_);
    if (created_streams_ > 0) --created_streams_;
  }
  streams_.erase(
      std::remove_if(streams_.begin(), streams_.end(),
                     [stream](const std::unique_ptr<TumStream>& s) { return s.get() == stream; }),
      streams_.end());
}

OniStatus TumDevice::setProperty(int property, const void* data, int size) {
  if (property == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION) {
    OniImageRegistrationMode mode;
    if (const OniStatus status = readProperty(data, size, mode); status != ONI_STATUS_OK)
      return status;
    // The recorded depth is registered already; it cannot be turned back.
    return mode == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR ? ONI_STATUS_OK : ONI_STATUS_NOT_SUPPORTED;
  }
  if (property == ONI_DEVICE_PROPERTY_PLAYBACK_SPEED && playsLikeRecording()) {
    float speed = 0;
    if (const OniStatus status = readProperty(data, size, speed); status != ONI_STATUS_OK)
      return status;
    if (!std::isfinite(speed)) return ONI_STATUS_BAD_PARAMETER;
    std::lock_guard<std::mutex> lock(state_mutex_);
    speed_ = speed;
    ++runs_;  // the time base restarts at the new speed
    state_changed_.notify_all();
    return ONI_STATUS_OK;
  }
  if (property == ONI_DEVICE_PROPERTY_PLAYBACK_REPEAT_ENABLED && playsLikeRecording()) {
    OniBool repeat = FALSE;
    if (const OniStatus status = readProperty(data, size, repeat); status != ONI_STATUS_OK)
      return status;
    camera_->setLooping(repeat == TRUE);
    return ONI_STATUS_OK;
  }
  return isPropertySupported(property) ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_NOT_IMPLEMENTED;
}

OniStatus TumDevice::getProperty(int property, void* data, int* size) {
  switch (property) {
    case ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION:
      return writeProperty(data, size, ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR);
    case ONI_DEVICE_PROPERTY_DRIVER_VERSION:
      return writeProperty(data, size, driverVersion());
    case ONI_DEVICE_PROPERTY_SERIAL_NUMBER:
      return writeProperty(data, size, std::string(camera_->info().name));
    case ONI_DEVICE_PROPERTY_PLAYBACK_SPEED: {
      if (!playsLikeRecording()) return ONI_STATUS_NOT_IMPLEMENTED;
      std::lock_guard<std::mutex> lock(state_mutex_);
      return writeProperty(data, size, speed_);
    }
    case ONI_DEVICE_PROPERTY_PLAYBACK_REPEAT_ENABLED:
      if (!playsLikeRecording()) return ONI_STATUS_NOT_IMPLEMENTED;
      return writeProperty(data, size, camera_->looping() ? OniBool(TRUE) : OniBool(FALSE));
    default:
      return ONI_STATUS_NOT_IMPLEMENTED;
  }
}

OniBool TumDevice::isPropertySupported(int property) {
  if (property == ONI_DEVICE_PROPERTY_PLAYBACK_SPEED ||
      property == ONI_DEVICE_PROPERTY_PLAYBACK_REPEAT_ENABLED)
    return playsLikeRecording() ? TRUE : FALSE;
  return property == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION ||
                 property == ONI_DEVICE_PROPERTY_DRIVER_VERSION ||
                 property == ONI_DEVICE_PROPERTY_SERIAL_NUMBER
             ? TRUE
             : FALSE;
}

OniStatus TumDevice::invoke(int command, void* data, int size) {
  if (command != ONI_DEVICE_COMMAND_SEEK || !playsLikeRecording()) return ONI_STATUS_NOT_SUPPORTED;
  OniSeek seek{};
  if (const OniStatus status = readProperty(data, size, seek); status != ONI_STATUS_OK)
    return status;
  if (!camera_->seek(seek.frameIndex)) return ONI_STATUS_BAD_PARAMETER;
  std::lock_guard<std::mutex> lock(state_mutex_);
  ++runs_;  // timing restarts from the pair sought
  reads_due_ = reads_;
  state_changed_.notify_all();
  return ONI_STATUS_OK;
}

OniBool TumDevice::isCommandSupported(int command) {
  return command == ONI_DEVICE_COMMAND_SEEK && playsLikeRecording() ? TRUE : FALSE;
}

OniStatus TumDevice::tryManualTrigger() {
  std::lock_guard<std::mutex> lock(state_mutex_);
  ++reads_;
  state_changed_.notify_all();
  return ONI_STATUS_OK;
}

int TumDevice::recordedFrames() const {
  return playsLikeRecording() ? static_cast<int>(camera_->size()) : 0;
}

OniBool TumDevice::isImageRegistrationModeSupported(OniImageRegistrationMode mode) {
  return mode == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR ? TRUE : FALSE;
}

bool TumDevice::streamStarted() {
  if (!camera_->plugged() || camera_->generation() != generation_) return false;
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (running_streams_++ == 0) ++runs_;
  state_changed_.notify_all();
  return true;
}

void TumDevice::streamStopped() {
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (running_streams_ > 0) --running_streams_;
  state_changed_.notify_all();
}

void TumDevice::play() {
  Frame frame;  // decoded into again and again: buffers are reused
  std::uint64_t run = 0;
  Clock::time_point run_start;
  double run_first_pace = 0.0;
  bool timed = false;
  bool first_of_run = true;
  bool poked_while_delivering = false;
  std::chrono::steady_clock::duration wait_for_poke = std::chrono::hours(24);
  std::unique_lock<std::mutex> lock(state_mutex_);
  while (true) {
    state_changed_.wait(lock, [this] { return closing_ || running_streams_ > 0; });
    if (closing_) return;
    if (runs_ != run) {
      run = runs_;
      timed = false;
    }
    lock.unlock();
    const std::optional<VirtualCamera::Shot> shot = camera_->peek(generation_);
    lock.lock();
    if (!shot) {
      // The end of a sequence that does not loop, or unplugged: nothing comes until a seek or
      // a restart (a new run).
      state_changed_.wait(lock, [this, run] { return closing_ || runs_ != run; });
      if (closing_) return;
      continue;
    }
    if (!timed) {
      run_start = Clock::now() + kFirstFrameDelay;
      run_first_pace = shot->pace_time;
      timed = true;
      first_of_run = true;
    }
    // Manual speed: the first pair of a run at its time, each next one once the last was read.
    const bool manual = speed_ <= 0;
    const double offset = manual ? 0.0 : (shot->pace_time - run_first_pace) / speed_;
    const Clock::time_point due = run_start + std::chrono::duration_cast<Clock::duration>(
                                                  std::chrono::duration<double>(offset));
    // Woken early by a stop, a restart or closing: the pair stays unplayed.
    if (state_changed_.wait_until(
            lock, due, [this, run] { return closing_ || runs_ != run || running_streams_ == 0; })) {
      if (closing_) return;
      continue;
    }
    // The first pair waits (a little) for every created stream to run, so none misses it and
    // then waits forever for a read that cannot come.
    if (manual && first_of_run)
      state_changed_.wait_for(lock, std::chrono::seconds(1), [this, run] {
        return closing_ || runs_ != run || running_streams_ >= created_streams_;
      });
    // A poke that came while the last pair was delivered was most likely the host finding the
    // pair half there; it asks again once it has read it. If it does not within
    // kUnansweredPokeWait, the poke was a real request that raced the end of the delivery.
    const auto asked = [this, run] {
      return closing_ || runs_ != run || running_streams_ == 0 || reads_ >= reads_due_;
    };
    if (manual && !first_of_run && !state_changed_.wait_for(lock, wait_for_poke, asked) &&
        !poked_while_delivering)
      continue;
    if (closing_) return;
    if (runs_ != run || running_streams_ == 0) continue;
    first_of_run = false;
    // In manual mode the next pair waits until the host asks for more (it waits for a frame
    // and none is left); a pair that could not be decoded is not waited for.
    lock.unlock();
    std::string error;
    const bool delivered = camera_->take(*shot, frame, error);
    lock.lock();
    const std::uint64_t reads_before = reads_;  // pokes from here on came during the delivery
    lock.unlock();
    if (delivered) {
      deliver(frame, *shot);
      if (camera_->countDelivered(generation_)) {
        log_.info(std::string(camera_->info().uri) + ": unplugged after " +
                  std::to_string(camera_->uri().disconnect_after) + " frames");
        on_unplugged_(camera_);
      }
    } else {
      log_.warning("skipping frame " + std::to_string(shot->frame_index) + ": " + error);
    }
    lock.lock();
    // Pokes that came while the pair was being handed out do not count as asking for the next:
    // the host pokes whenever it finds nothing, including when it saw the depth of this pair
    // but not yet its colour. Counting those ran the player a pair ahead of a slow host, whose
    // unread frames the next pair then replaced.
    reads_due_ = delivered ? reads_ + 1 : reads_;
    poked_while_delivering = delivered && reads_ != reads_before;
    wait_for_poke = poked_while_delivering ? kUnansweredPokeWait : std::chrono::hours(24);
  }
}

void TumDevice::deliver(const Frame& frame, const VirtualCamera::Shot& shot) {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  for (const std::unique_ptr<TumStream>& stream : streams_) stream->deliver(frame, shot);
}

}  // namespace rgbdmap::openni2_tum
