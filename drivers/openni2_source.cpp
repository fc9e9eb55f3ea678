#include "rgbdmap/drivers/openni2_source.hpp"

#include <OpenNI.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "openni2/open_device.hpp"
#include "openni2/reconnect_backoff.hpp"
#include "openni2/runtime.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/accelerometer_log.hpp"
#include "rgbdmap/drivers/kinect_accelerometer.hpp"

namespace rgbdmap {
namespace {

using Clock = std::chrono::steady_clock;
using openni2::kReadTimeout;
using openni2::OpenDevice;

// Reopening a camera that went away: at once, then after 0.5 s, 1 s, 2 s, 4 s, 5 s, 5 s...;
// reconnect() returns at least this often while it waits.
constexpr std::chrono::milliseconds kReconnectFirstDelay{500};
constexpr std::chrono::milliseconds kReconnectLongestDelay{5000};
constexpr std::chrono::milliseconds kReconnectPoll{250};
// Depth and colour of one moment: TUM's association rule (0.02 s), over half a 30 fps frame.
constexpr std::int64_t kPairingToleranceUs = 20000;

// Reads paired depth and colour frames from an OpenNI2 device or recording, reopens a device
// that went away.
class OpenNI2Source : public FrameSource {
 public:
  OpenNI2Source(const std::string& uri_or_file, const CameraOptions& camera, double rate)
      : runtime_(openni2::Runtime::acquire()),
        requested_(uri_or_file),
        settings_{camera, camera.intrinsics == "device"},
        rate_(rate) {
    open(requested_, true);
    reopen_uri_ = dev_->uri();
  }
  ~OpenNI2Source() override { close(); }

  ReadStatus read(Frame& frame) override;
  CameraIntrinsics intrinsics() const override { return camera_; }
  bool isLive() const override { return !is_file_; }
  bool providesPoses() const override { return false; }
  std::string describe() const override;
  std::uint64_t skipped() const override { return skipped_; }
  bool canReconnect() const override { return !is_file_; }
  bool reconnect() override;

 private:
  const std::string& label() const { return label_; }
  // Opens and starts the device; throws InputError (with the USB diagnosis for
  // "" when `diagnose`). Leaves everything closed when it throws.
  void open(const std::string& uri, bool diagnose);
  void close();
  void pace(double stamp);
  void readUp(Frame& frame);

  // Declared first so that it is released last: OpenNI2 shuts down after
  // everything below.
  std::shared_ptr<openni2::Runtime> runtime_;
  const std::string requested_;
  const openni2::DeviceSettings settings_;
  const double rate_;

  std::string reopen_uri_;  // the device reconnect() looks for
  std::string label_;       // "openni2:URI" or "openni2:FILE.oni", for messages and
                            // Frame::origin (kept while closed)
  std::string name_;        // vendor and model
  bool is_file_ = false;
  bool has_accelerometer_ = false;  // the Kinect driver with its motor's device
  bool open_ = false;
  bool ever_opened_ = false;
  std::unique_ptr<OpenDevice> dev_;  // null while closed
  openni2::ReconnectBackoff backoff_{kReconnectFirstDelay, kReconnectLongestDelay};

  CameraIntrinsics camera_;
  int depth_total_ = 0;  // frames in a recording (0 = unknown)
  int color_total_ = 0;
  bool repeats_ = false;  // a recording that loops never ends by its frame count
  int depth_read_ = 0;
  int color_read_ = 0;
  bool ended_ = false;
  std::uint64_t skipped_ = 0;
  bool paced_ = false;
  double first_stamp_ = 0;
  Clock::time_point first_time_;
};

void OpenNI2Source::open(const std::string& uri, bool diagnose) {
  std::unique_ptr<OpenDevice> dev =
      OpenDevice::open(runtime_, uri, requested_, settings_, diagnose);
  const CameraIntrinsics& camera = dev->intrinsics();
  if (ever_opened_ && (camera.width != camera_.width || camera.height != camera_.height)) {
    const std::string message = dev->label() + ": came back as " + std::to_string(camera.width) +
                                "x" + std::to_string(camera.height) + " instead of " +
                                std::to_string(camera_.width) + "x" +
                                std::to_string(camera_.height);
    OpenDevice::close(std::move(dev));
    throw InputError(message);
  }
  if (!ever_opened_) camera_ = camera;
  dev_ = std::move(dev);
  is_file_ = dev_->isFile();
  has_accelerometer_ = dev_->device().isPropertySupported(kKinectAccelerationProperty);
  label_ = dev_->label();
  name_ = dev_->name();
  depth_total_ = dev_->depthTotal();
  color_total_ = dev_->colorTotal();
  repeats_ = dev_->repeats();
  depth_read_ = color_read_ = 0;
  ended_ = false;
  paced_ = false;
  open_ = true;
  ever_opened_ = true;
}

void OpenNI2Source::close() {
  open_ = false;
  OpenDevice::close(std::move(dev_));
}

std::string OpenNI2Source::describe() const {
  const std::string size = std::to_string(camera_.width) + "x" + std::to_string(camera_.height);
  if (is_file_)
    return label() + " (recording, " + std::to_string(depth_total_) + " depth + " +
           std::to_string(color_total_) + " colour frames, " + size + ")";
  return label() + " (" + name_ + ", " + size + ")";
}

ReadStatus OpenNI2Source::read(Frame& frame) {
  if (ended_) return ReadStatus::kEnd;
  if (!open_)
    return ReadStatus::kTimeout;  // still unplugged: reconnect() has not
                                  // succeeded
  openni::VideoStream* streams[] = {&dev_->depth(), &dev_->color()};
  bool have_depth = false;
  bool have_color = false;
  bool wrong_size = false;
  std::uint64_t depth_stamp = 0;  // device clock, µs
  std::uint64_t color_stamp = 0;
  const Clock::time_point deadline = Clock::now() + kReadTimeout;
  // Frames the camera sent before it was unplugged are still read: the unplug is reported only
  // when nothing is waiting (a run that starts reading late still maps the camera's last frames).
  while (!have_depth || !have_color) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) {
      if (!is_file_) return ReadStatus::kTimeout;
      // The frame counts promised more than the file holds (a truncated
      // recording).
      spdlog::warn(
          "{}: no frame for {} s after {} depth and {} colour frames of {} + {}; taking it as the "
          "end of the recording",
          label(), kReadTimeout.count() / 1000.0, depth_read_, color_read_, depth_total_,
          color_total_);
      ended_ = true;
      return ReadStatus::kEnd;
    }
    // Short waits, so an unplug event is noticed promptly.
    int ready = -1;
    const int wait_ms = static_cast<int>(std::min<long>(left.count(), 100));
    const bool gone = dev_->watch() && dev_->watch()->disconnected();
    const openni::Status status =
        openni::OpenNI::waitForAnyStream(streams, 2, &ready, gone ? 0 : wait_ms);
    if (status != openni::STATUS_OK && gone) {
      spdlog::warn("{}: OpenNI2 reports the device disconnected", label());
      return ReadStatus::kTimeout;
    }
    if (status == openni::STATUS_TIME_OUT) continue;
    if (status != openni::STATUS_OK) {
      spdlog::debug("{}: waiting for frames: {}", label(), openni2::lastError());
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    openni::VideoStream& stream = ready == 0 ? dev_->depth() : dev_->color();
    openni::VideoFrameRef& ref = ready == 0 ? dev_->depthFrame() : dev_->colorFrame();
    if (stream.readFrame(&ref) != openni::STATUS_OK || !ref.isValid()) continue;
    const int width = ref.getWidth();
    const int height = ref.getHeight();
    if (width != camera_.width || height != camera_.height) wrong_size = true;
    if (ready == 0) {
      ++depth_read_;
      have_depth = true;
      depth_stamp = ref.getTimestamp();
      if (wrong_size) continue;
      // In place: the Frame's images keep their buffers (same size and type
      // every time).
      const cv::Mat units(height, width, CV_16UC1, const_cast<void*>(ref.getData()),
                          static_cast<std::size_t>(ref.getStrideInBytes()));
      units.convertTo(frame.depth, CV_32F, dev_->metresPerUnit());
    } else {
      ++color_read_;
      have_color = true;
      color_stamp = ref.getTimestamp();
      if (wrong_size) continue;
      const cv::Mat rgb(height, width, CV_8UC3, const_cast<void*>(ref.getData()),
                        static_cast<std::size_t>(ref.getStrideInBytes()));
      cv::cvtColor(rgb, frame.color, cv::COLOR_RGB2BGR);
      frame.timestamp = static_cast<double>(ref.getTimestamp()) * 1e-6;  // device clock, µs
    }
    // A live camera's depth and colour are paired by their stamps, not by trusting frame sync
    // (which not every driver offers): the older of two frames too far apart is read again.
    if (!is_file_ && have_depth && have_color && !wrong_size) {
      const std::int64_t gap =
          static_cast<std::int64_t>(depth_stamp) - static_cast<std::int64_t>(color_stamp);
      if (gap > kPairingToleranceUs) {
        have_color = false;
      } else if (-gap > kPairingToleranceUs) {
        have_depth = false;
      }
    }
  }
  if (is_file_ && !repeats_ && (depth_read_ >= depth_total_ || color_read_ >= color_total_))
    ended_ = true;
  if (wrong_size) {
    spdlog::warn("{}: skipping a frame of {}x{} (depth) / {}x{} (colour); the camera is {}x{}",
                 label(), dev_->depthFrame().getWidth(), dev_->depthFrame().getHeight(),
                 dev_->colorFrame().getWidth(), dev_->colorFrame().getHeight(), camera_.width,
                 camera_.height);
    ++skipped_;
    return ReadStatus::kSkipped;
  }
  frame.has_pose = false;
  readUp(frame);
  frame.origin = label();
  backoff_.reset();  // frames flow: the next outage starts backing off afresh
  if (is_file_ && rate_ > 0) pace(frame.timestamp);
  return ReadStatus::kFrame;
}

// The camera's up from its accelerometer where the driver offers one: the sample read after the
// latest depth frame (within a frame of this pair; the mapper averages over keyframes).
void OpenNI2Source::readUp(Frame& frame) {
  frame.has_up = false;
  if (!has_accelerometer_) return;
  KinectAcceleration sample;
  int size = sizeof sample;
  if (dev_->device().getProperty(kKinectAccelerationProperty, &sample, &size) !=
          openni::STATUS_OK ||
      size != static_cast<int>(sizeof sample))
    return;
  if (const auto up = AccelerometerLog::upFromSample({sample.x, sample.y, sample.z})) {
    frame.has_up = true;
    frame.up = *up;
  }
}

// Releases recorded frames at their recorded spacing divided by replay.rate.
void OpenNI2Source::pace(double stamp) {
  if (!paced_) {
    paced_ = true;
    first_stamp_ = stamp;
    first_time_ = Clock::now();
    return;
  }
  const double offset = std::max(0.0, (stamp - first_stamp_) / rate_);
  std::this_thread::sleep_until(first_time_ + std::chrono::duration_cast<Clock::duration>(
                                                  std::chrono::duration<double>(offset)));
}

bool OpenNI2Source::reconnect() {
  if (open_) close();
  // Returns within kReconnectPoll while waiting for the next attempt, so the caller can stop.
  Clock::time_point now = Clock::now();
  if (!backoff_.due(now)) {
    std::this_thread::sleep_for(std::min<Clock::duration>(backoff_.next() - now, kReconnectPoll));
    now = Clock::now();
    if (!backoff_.due(now)) return false;
  }
  // A replugged camera may get a new USB address and URI; when the user asked
  // for "the first camera", any camera will do.
  std::vector<std::string> candidates{reopen_uri_};
  if (requested_.empty()) candidates.push_back("");
  std::string last_error;
  for (const std::string& uri : candidates) {
    try {
      open(uri, false);
      backoff_.succeeded();
      spdlog::info("{}: reopened (reopen attempt {})", label(), backoff_.attempts());
      return true;
    } catch (const InputError& e) {
      last_error = e.what();
    }
  }
  backoff_.failed(now);
  spdlog::info("openni2:{}: not back yet (reopen attempt {}: {}); next attempt in {:.1f} s",
               reopen_uri_, backoff_.attempts(), last_error,
               std::chrono::duration<double>(backoff_.next() - now).count());
  return false;
}

}  // namespace

std::unique_ptr<FrameSource> openOpenNI2Source(const std::string& uri_or_file,
                                               const CameraOptions& camera, double rate) {
  return std::make_unique<OpenNI2Source>(uri_or_file, camera, rate);
}

std::vector<std::string> listOpenNI2Devices() {
  const std::shared_ptr<openni2::Runtime> runtime = openni2::Runtime::acquire();
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  std::vector<std::string> list;
  for (int i = 0; i < devices.getSize(); ++i) {
    char ids[16];
    std::snprintf(ids, sizeof ids, "%04x:%04x", devices[i].getUsbVendorId(),
                  devices[i].getUsbProductId());
    list.push_back(std::string(devices[i].getUri()) + " (" + devices[i].getVendor() + " " +
                   devices[i].getName() + ", USB " + ids + ")");
  }
  return list;
}

std::string openNI2CameraModel(const std::string& uri) {
  try {
    const std::shared_ptr<openni2::Runtime> runtime = openni2::Runtime::acquire();
    openni::Array<openni::DeviceInfo> devices;
    openni::OpenNI::enumerateDevices(&devices);
    for (int i = 0; i < devices.getSize(); ++i) {
      const openni::DeviceInfo& info = devices[i];
      if (!uri.empty() && uri != info.getUri()) continue;
      const std::string name = std::string(info.getVendor()) + " " + info.getName();
      const bool primesense =
          info.getUsbVendorId() == 0x1d27 || name.find("PrimeSense") != std::string::npos ||
          name.find("Xtion") != std::string::npos || name.find("Carmine") != std::string::npos;
      return primesense ? "xtion" : "kinect_v1";
    }
  } catch (const InputError&) {
    // OpenNI2 cannot start: opening the source will say so.
  }
  return "";
}

}  // namespace rgbdmap
