#include "kinect_device.hpp"

#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>

#include "rgbdmap/drivers/oni_property.hpp"

namespace rgbdmap::openni2_freenect {
namespace {

static_assert(sizeof(freenect_raw_tilt_state) == sizeof(FakenectTiltState),
              "record --format fakenect writes accelerometer records of this size");

}  // namespace

KinectDevice::KinectDevice(int index, std::function<void()> on_unplugged)
    : on_unplugged_(std::move(on_unplugged)),
      depth_modes_(KinectStream::depthModes()),
      color_modes_(KinectStream::colorModes()),
      depth_buffer_(static_cast<std::size_t>(KinectV1Model::kWidth) * KinectV1Model::kHeight),
      video_buffer_(static_cast<std::size_t>(KinectV1Model::kWidth) * KinectV1Model::kHeight * 3) {
  sensors_[0] = {ONI_SENSOR_DEPTH, static_cast<int>(depth_modes_.size()), depth_modes_.data()};
  sensors_[1] = {ONI_SENSOR_COLOR, static_cast<int>(color_modes_.size()), color_modes_.data()};
  if (freenect_init(&context_, nullptr) < 0) throw std::runtime_error("libfreenect cannot start");
  // With the motor's device when it opens (it holds the accelerometer); some Kinects (model
  // 1473) and some USB set-ups refuse it, and the cameras still work without.
  freenect_select_subdevices(
      context_, static_cast<freenect_device_flags>(FREENECT_DEVICE_CAMERA | FREENECT_DEVICE_MOTOR));
  has_motor_ = freenect_open_device(context_, &device_, index) >= 0;
  if (!has_motor_) freenect_select_subdevices(context_, FREENECT_DEVICE_CAMERA);
  if (!has_motor_ && freenect_open_device(context_, &device_, index) < 0) {
    freenect_shutdown(context_);
    throw std::runtime_error("libfreenect cannot open Kinect " + std::to_string(index) +
                             " (unplugged, or in use by another program?)");
  }
  freenect_set_user(device_, this);
  freenect_set_depth_mode(
      device_, freenect_find_depth_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_DEPTH_11BIT));
  freenect_set_video_mode(device_,
                          freenect_find_video_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_VIDEO_RGB));
  freenect_set_depth_buffer(device_, depth_buffer_.data());
  freenect_set_video_buffer(device_, video_buffer_.data());
  freenect_set_depth_callback(device_, &KinectDevice::onDepth);
  freenect_set_video_callback(device_, &KinectDevice::onVideo);
}

KinectDevice::~KinectDevice() {
  stopEvents();
  freenect_stop_depth(device_);
  freenect_stop_video(device_);
  freenect_close_device(device_);
  freenect_shutdown(context_);
}

OniStatus KinectDevice::getSensorInfoList(OniSensorInfo** sensors, int* count) {
  if (sensors == nullptr || count == nullptr) return ONI_STATUS_BAD_PARAMETER;
  *sensors = sensors_;
  *count = 2;
  return ONI_STATUS_OK;
}

oni::driver::StreamBase* KinectDevice::createStream(OniSensorType type) {
  std::lock_guard<std::mutex> lock(mutex_);
  StreamHost& host = *this;
  if (type == ONI_SENSOR_DEPTH && !depth_) {
    depth_ = std::make_unique<KinectDepthStream>(host, model_);
    ++created_;
    return depth_.get();
  }
  if (type == ONI_SENSOR_COLOR && !color_) {
    color_ = std::make_unique<KinectColorStream>(host);
    ++created_;
    return color_.get();
  }
  return nullptr;  // no infrared stream; one stream of each kind
}

void KinectDevice::destroyStream(oni::driver::StreamBase* stream) {
  if (stream == nullptr) return;
  stream->stop();
  // Under the lock: a libfreenect callback delivers to a stream only while holding it.
  std::lock_guard<std::mutex> lock(mutex_);
  if (stream == depth_.get()) {
    depth_.reset();
    --created_;
  } else if (stream == color_.get()) {
    color_.reset();
    --created_;
  }
}

OniStatus KinectDevice::setProperty(int property, const void* data, int size) {
  if (property != ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION) return ONI_STATUS_NOT_IMPLEMENTED;
  OniImageRegistrationMode mode;
  if (const OniStatus status = readProperty(data, size, mode); status != ONI_STATUS_OK)
    return status;
  if (mode != ONI_IMAGE_REGISTRATION_OFF && mode != ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR)
    return ONI_STATUS_NOT_SUPPORTED;
  registered_.store(mode == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR);
  return ONI_STATUS_OK;
}

OniStatus KinectDevice::getProperty(int property, void* data, int* size) {
  if (property == kKinectAccelerationProperty && has_motor_) {
    if (data == nullptr || size == nullptr || *size != static_cast<int>(sizeof acceleration_))
      return ONI_STATUS_BAD_PARAMETER;
    std::lock_guard<std::mutex> lock(acceleration_mutex_);
    if (!has_acceleration_) return ONI_STATUS_NO_DEVICE;  // no depth frame yet
    std::memcpy(data, &acceleration_, sizeof acceleration_);
    return ONI_STATUS_OK;
  }
  if (property != ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION) return ONI_STATUS_NOT_IMPLEMENTED;
  const OniImageRegistrationMode mode =
      registered_.load() ? ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR : ONI_IMAGE_REGISTRATION_OFF;
  if (data == nullptr || size == nullptr || *size != static_cast<int>(sizeof mode))
    return ONI_STATUS_BAD_PARAMETER;
  std::memcpy(data, &mode, sizeof mode);
  return ONI_STATUS_OK;
}

OniBool KinectDevice::isPropertySupported(int property) {
  if (property == kKinectAccelerationProperty) return has_motor_ ? TRUE : FALSE;
  return property == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION ? TRUE : FALSE;
}

OniBool KinectDevice::isImageRegistrationModeSupported(OniImageRegistrationMode mode) {
  return mode == ONI_IMAGE_REGISTRATION_OFF || mode == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR
             ? TRUE
             : FALSE;
}

bool KinectDevice::streamStarted(OniSensorType type) {
  if (gone_.load()) return false;
  std::lock_guard<std::mutex> lock(mutex_);
  const int started =
      type == ONI_SENSOR_DEPTH ? freenect_start_depth(device_) : freenect_start_video(device_);
  if (started < 0) return false;
  (type == ONI_SENSOR_DEPTH ? depth_running_ : video_running_) = true;
  if (!events_.joinable()) {
    stopping_events_ = false;
    events_ = std::thread([this] { runEvents(); });
  }
  changed_.notify_all();
  return true;
}

void KinectDevice::streamStopped(OniSensorType type) {
  bool none_running = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (type == ONI_SENSOR_DEPTH) {
      depth_running_ = false;
      freenect_stop_depth(device_);
    } else {
      video_running_ = false;
      freenect_stop_video(device_);
    }
    none_running = !depth_running_ && !video_running_;
  }
  if (none_running) stopEvents();
}

void KinectDevice::stopEvents() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_events_ = true;
    changed_.notify_all();
  }
  if (events_.joinable() && events_.get_id() != std::this_thread::get_id()) events_.join();
}

void KinectDevice::runEvents() {
  {
    // Every created stream gets the first frames (fakenect plays on as soon as events run):
    // wait a little for the rest to start.
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait_for(lock, std::chrono::seconds(1), [this] {
      return stopping_events_ || (depth_running_ ? 1 : 0) + (video_running_ ? 1 : 0) >= created_;
    });
  }
  timeval timeout{0, 100 * 1000};
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_events_) return;
    }
    if (freenect_process_events_timeout(context_, &timeout) < 0) {
      gone_.store(true);
      on_unplugged_();
      return;
    }
    if (has_motor_ && depth_arrived_.exchange(false)) readAccelerometer();
  }
}

// Once per depth frame, outside libfreenect's callbacks: the read is a blocking USB control
// transfer on the motor's device (fakenect instead replays the dump's last 'a' record).
void KinectDevice::readAccelerometer() {
  if (freenect_update_tilt_state(device_) < 0) return;
  freenect_raw_tilt_state* state = freenect_get_tilt_state(device_);
  if (state == nullptr) return;
  KinectAcceleration sample;
  freenect_get_mks_accel(state, &sample.x, &sample.y, &sample.z);
  std::lock_guard<std::mutex> lock(acceleration_mutex_);
  acceleration_ = sample;
  has_acceleration_ = true;
}

void KinectDevice::onDepth(freenect_device* device, void* data, std::uint32_t /*timestamp*/) {
  auto* self = static_cast<KinectDevice*>(freenect_get_user(device));
  self->depth_arrived_.store(true);
  std::lock_guard<std::mutex> lock(self->mutex_);
  if (self->depth_) self->depth_->deliverRaw(static_cast<const std::uint16_t*>(data));
}

void KinectDevice::onVideo(freenect_device* device, void* data, std::uint32_t /*timestamp*/) {
  auto* self = static_cast<KinectDevice*>(freenect_get_user(device));
  std::lock_guard<std::mutex> lock(self->mutex_);
  if (self->color_) self->color_->deliverRgb(static_cast<const std::uint8_t*>(data));
}

}  // namespace rgbdmap::openni2_freenect
