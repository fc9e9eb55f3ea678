#include "rgbdmap/ros/topic_source.hpp"

#include <spdlog/spdlog.h>
#include <std_msgs/UInt64MultiArray.h>

#include <chrono>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/ros/image_messages.hpp"

namespace rgbdmap {
namespace {

// Pairs kept for the capture thread (a quarter second at 30 Hz, before the pipeline's own queue):
// more means mapping is behind, and the oldest go.
constexpr std::size_t kReadyPairs = 8;
// Until mapping starts reading (its start-up takes a moment once the first images are in), pairs
// are kept up to ten seconds' worth: a short recording must not lose its first second.
constexpr std::size_t kStartupPairs = 300;
// Images a subscriber queues while the callback thread is not scheduled (a loaded machine).
constexpr std::uint32_t kSubscriberQueue = 10;
// Without frames for this long read() reports a timeout (the pipeline checkpoints and waits).
constexpr double kFrameTimeout = 2.0;
// Without new images for this long, the images still waiting for a partner are paired.
constexpr double kSettleTimeout = 0.5;
// How long the first images may wait for their camera_info.
constexpr double kCameraInfoGrace = 3.0;

double stampOf(const sensor_msgs::Image& msg) {
  return stampSeconds(msg.header.stamp.sec, msg.header.stamp.nsec);
}

}  // namespace

TopicSource::TopicSource(ros::NodeHandle& nh, const Config& config, const std::atomic<bool>& stop,
                         bool lossless)
    : config_(config), stop_(stop), lossless_(lossless), camera_(config.camera) {
  // Advertised before subscribing: a player that waits for the node's subscriptions finds it.
  // Latched: a player that connects late still learns where the node is (else it would wait for
  // a pair the node has already taken).
  if (lossless_)
    intake_pub_ = ros::NodeHandle("~").advertise<std_msgs::UInt64MultiArray>("intake", 1, true);
  // Large images: a short subscriber queue (the pairer holds a window of its own), no Nagle.
  // Lossless, no image may be dropped on the way in: the queue is unbounded, and the player's
  // pacing by ~intake keeps it short (rgbdmap-play).
  const std::uint32_t queue = lossless_ ? 0 : kSubscriberQueue;
  const ros::TransportHints hints = ros::TransportHints().tcpNoDelay();
  color_sub_ = nh.subscribe(kColorTopic, queue, &TopicSource::onColor, this, hints);
  depth_sub_ = nh.subscribe(kDepthTopic, queue, &TopicSource::onDepth, this, hints);
  info_sub_ = nh.subscribe(kCameraInfoTopic, 1, &TopicSource::onCameraInfo, this);
  color_topic_ = color_sub_.getTopic();
  depth_topic_ = depth_sub_.getTopic();
  info_topic_ = info_sub_.getTopic();
}

void TopicSource::shutdown() {
  color_sub_.shutdown();
  depth_sub_.shutdown();
  info_sub_.shutdown();
}

void TopicSource::onColor(const ImagePtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.color_received;
  // seq counts a publisher's messages: a gap is an image lost on the way (a subscriber queue
  // overflowing, the network); a restart of the publisher starts again lower.
  if (last_color_seq_ && msg->header.seq > *last_color_seq_)
    counts_.color_lost += msg->header.seq - *last_color_seq_ - 1;
  last_color_seq_ = msg->header.seq;
  if (camera_frame_.empty()) camera_frame_ = msg->header.frame_id;
  pairer_.addColor(stampOf(*msg), msg);
  takePairs();
  publishIntake();
}

void TopicSource::onDepth(const ImagePtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.depth_received;
  pairer_.addDepth(stampOf(*msg), msg);
  takePairs();
  publishIntake();
}

void TopicSource::publishIntake() {
  if (!lossless_) return;
  std_msgs::UInt64MultiArray intake;
  intake.data = {counts_.color_received, counts_.depth_received, taken_, last_taken_.toNSec()};
  intake_pub_.publish(intake);
}

bool TopicSource::inputEnded() const {
  return color_sub_.getNumPublishers() == 0 && depth_sub_.getNumPublishers() == 0;
}

bool TopicSource::waitForNextPair() {
  if (!lossless_) {
    // The newest images settle into pairs only when later ones arrive: when the camera pauses
    // (a bag played to its end) they are paired after a short wait instead of never.
    return waitForPair(kSettleTimeout) ||
           (!stop_.load() && (flushPairs() || waitForPair(kFrameTimeout - kSettleTimeout)));
  }
  // Lossless, a pause is a player waiting for the node or held up by a busy machine, not the
  // end: the newest images are paired once the player has gone (it leaves once the node has
  // received everything it sent), and only then does the input fall silent.
  while (!stop_.load()) {
    if (waitForPair(0.1)) return true;
    if (inputEnded()) return flushPairs();
  }
  return false;
}

void TopicSource::onCameraInfo(const sensor_msgs::CameraInfo::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!info_) {
    info_ = *msg;
    arrived_.notify_all();
  }
}

void TopicSource::takePairs() {
  Pair pair;
  bool any = false;
  while (pairer_.next(pair)) {
    ++counts_.paired;
    ready_.push_back(std::move(pair));
    if (!lossless_ && ready_.size() > (reading_ ? kReadyPairs : kStartupPairs)) {
      ready_.pop_front();
      ++counts_.buffer_dropped;
    }
    any = true;
  }
  if (any) arrived_.notify_all();
}

bool TopicSource::waitForPair(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  std::unique_lock<std::mutex> lock(mutex_);
  // Short waits: a stop must not wait for the timeout.
  while (ready_.empty() && !stop_.load() && std::chrono::steady_clock::now() < deadline)
    arrived_.wait_for(lock, std::chrono::milliseconds(100));
  return !ready_.empty();
}

bool TopicSource::waitForCamera() {
  spdlog::info("waiting for {} and {} ...", color_topic_, depth_topic_);
  while (!stop_.load() && !waitForPair(1.0)) {
  }
  if (stop_.load()) return false;
  Pair first;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    first = ready_.front();
  }
  if (const std::string p = colorEncodingProblem(first.color->encoding); !p.empty())
    throw InputError(color_topic_ + ": " + p);
  if (const std::string p = depthEncodingProblem(first.depth->encoding); !p.empty())
    throw InputError(depth_topic_ + ": " + p);
  intrinsics_from_ = "preset " + config_.preset;
  if (intrinsicsFromCameraInfoWanted(config_)) {
    std::unique_lock<std::mutex> lock(mutex_);
    arrived_.wait_for(lock, std::chrono::duration<double>(kCameraInfoGrace),
                      [&] { return info_.has_value() || stop_.load(); });
    if (info_ && info_->K[0] > 0 && info_->K[4] > 0) {
      camera_ = intrinsicsFromCameraInfo(*info_);
      intrinsics_from_ = info_topic_;
    } else {
      spdlog::warn("{}: no usable camera_info within {} s; using the {} preset's intrinsics",
                   info_topic_, kCameraInfoGrace, config_.preset);
    }
  }
  if (static_cast<int>(first.depth->width) != camera_.width ||
      static_cast<int>(first.depth->height) != camera_.height) {
    spdlog::warn("{}: images are {}x{}, the camera is {}x{}: mapping at the images' size",
                 depth_topic_, first.depth->width, first.depth->height, camera_.width,
                 camera_.height);
    // Intrinsics scale with the image (a camera driver set to another resolution).
    const double sx = static_cast<double>(first.depth->width) / camera_.width;
    const double sy = static_cast<double>(first.depth->height) / camera_.height;
    camera_.fx *= sx, camera_.cx = (camera_.cx + 0.5) * sx - 0.5;
    camera_.fy *= sy, camera_.cy = (camera_.cy + 0.5) * sy - 0.5;
    camera_.width = static_cast<int>(first.depth->width);
    camera_.height = static_cast<int>(first.depth->height);
  }
  return true;
}

void TopicSource::skip(const std::string& reason, const std::string& detail) {
  spdlog::warn("skipping a frame: {}", detail);
  std::lock_guard<std::mutex> lock(mutex_);
  reasons_.add(reason, detail);
  ++skipped_;
}

bool TopicSource::flushPairs() {
  std::lock_guard<std::mutex> lock(mutex_);
  Pair pair;
  while (pairer_.next(pair, true)) {
    ++counts_.paired;
    ready_.push_back(std::move(pair));
  }
  return !ready_.empty();
}

ReadStatus TopicSource::read(Frame& frame) {
  if (!waitForNextPair()) {
    // A stop while waiting is the end of the stream, not a camera that went away.
    if (stop_.load()) return ReadStatus::kEnd;
    logCounts();
    return ReadStatus::kTimeout;
  }
  if (stop_.load() && !waitForPair(0)) return ReadStatus::kEnd;
  Pair pair;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    reading_ = true;
    pair = std::move(ready_.front());
    ready_.pop_front();
    ++taken_;
    last_taken_ = pair.color->header.stamp;
    publishIntake();
  }
  std::string error;
  if (!depthFromMessage(*pair.depth, frame.depth, error)) {
    skip("depth image: " + error, depth_topic_ + ": " + error);
    return ReadStatus::kSkipped;
  }
  if (!colorFromMessage(*pair.color, frame.color, error)) {
    skip("colour image: " + error, color_topic_ + ": " + error);
    return ReadStatus::kSkipped;
  }
  if (frame.depth.size() != frame.color.size() || frame.depth.cols != camera_.width ||
      frame.depth.rows != camera_.height) {
    skip("image size differs from the colour image or the camera",
         depth_topic_ + ": depth " + std::to_string(frame.depth.cols) + "x" +
             std::to_string(frame.depth.rows) + ", colour " + std::to_string(frame.color.cols) +
             "x" + std::to_string(frame.color.rows) + ", camera " + std::to_string(camera_.width) +
             "x" + std::to_string(camera_.height));
    return ReadStatus::kSkipped;
  }
  frame.timestamp = pair.color_time;
  frame.has_pose = false;
  frame.has_up = false;
  frame.origin = color_topic_;
  return ReadStatus::kFrame;
}

void TopicSource::logCounts() const {
  const Counts c = counts();
  spdlog::info(
      "{}: camera silent after {} colour and {} depth images ({} colour lost before the node): {} "
      "pairs, {} dropped in the node's buffer, {} images unpaired",
      color_topic_, c.color_received, c.depth_received, c.color_lost, c.paired, c.buffer_dropped,
      c.unmatched);
}

bool TopicSource::reconnect() {
  // Lossless, a new player may come (the next bag): its images are paired as they arrive.
  return waitForPair(1.0) || ((!lossless_ || inputEnded()) && flushPairs());
}

std::string TopicSource::describe() const {
  return "ros:" + color_topic_ + " + " + depth_topic_ + " (intrinsics from " + intrinsics_from_ +
         ")";
}

std::uint64_t TopicSource::skipped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return skipped_;
}

std::vector<SkipReasons::Entry> TopicSource::skipReasons() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return reasons_.entries();
}

std::string TopicSource::cameraFrame() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return camera_frame_;
}

TopicSource::Counts TopicSource::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Counts c = counts_;
  c.unmatched = pairer_.unmatched();
  return c;
}

}  // namespace rgbdmap
