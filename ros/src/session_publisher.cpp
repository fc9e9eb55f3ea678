#include "rgbdmap/ros/session_publisher.hpp"

#include <spdlog/spdlog.h>
#include <std_msgs/UInt8MultiArray.h>

#include <algorithm>
#include <chrono>
#include <random>

#include "rgbdmap/base/steady_time.hpp"

namespace rgbdmap {
namespace {

// A run's id: another on every start, so that a merger tells a restarted robot's stream from
// the one before.
std::uint64_t newRunId() {
  std::random_device device;
  const auto clock =
      static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count());
  return ((static_cast<std::uint64_t>(device()) << 32) | device()) ^ clock;
}

}  // namespace

SessionPublisher::SessionPublisher(ros::NodeHandle& private_nh, Options options)
    : options_(options), run_(newRunId()) {
  // Not latched and deep: every record counts (a lost one makes the merger ask again).
  graph_pub_ = private_nh.advertise<std_msgs::UInt8MultiArray>("session/graph", 100);
  places_pub_ = private_nh.advertise<std_msgs::UInt8MultiArray>("session/places", 100);
  pieces_pub_ = private_nh.advertise<std_msgs::UInt8MultiArray>("session/pieces", 100);
  thread_ = std::thread([this] { loop(); });
}

SessionPublisher::~SessionPublisher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    graph_ = nullptr;
  }
  wake_.notify_all();
  thread_.join();
}

void SessionPublisher::attach(const LoopCloser* graph, const CameraIntrinsics& camera) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (graph && !stream_) {
    stream_ = std::make_unique<SessionStream>(run_, camera, options_.stream);
    started_ = steadySeconds();
  }
  attached_.store(graph != nullptr);
  if (!graph) {
    // A tracking thread waiting for room (lossless) waits no more: nothing is taken from now on.
    { std::lock_guard<std::mutex> incoming(incoming_mutex_); }
    room_.notify_all();
  }
  if (!graph && graph_ && stream_) {
    // What the budget still allows goes out before the graph is let go.
    send(steadySeconds());
    totals_ = stream_->totals();
    std::uint64_t dropped = 0;
    {
      std::lock_guard<std::mutex> incoming(incoming_mutex_);
      dropped = pieces_dropped_;
    }
    const double seconds = std::max(1e-3, steadySeconds() - started_);
    spdlog::info(
        "session stream: {} keyframes, {} edges, {} places and {} map pieces ({:.1f} MB) sent, "
        "{:.1f} MB in {:.0f} s ({:.0f} KB/s){}",
        totals_.keyframes, totals_.edges, totals_.places, totals_.pieces, totals_.piece_bytes / 1e6,
        totals_.bytes / 1e6, seconds, totals_.bytes / 1e3 / seconds,
        dropped > 0 ? fmt::format("; {} keyframes not sent (the queue was full)", dropped) : "");
  }
  graph_ = graph;
  wake_.notify_all();
}

SessionStream::Totals SessionPublisher::totals() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stream_ ? stream_->totals() : totals_;
}

std::uint64_t SessionPublisher::keyframesDropped() const {
  std::lock_guard<std::mutex> lock(incoming_mutex_);
  return pieces_dropped_;
}

void SessionPublisher::addKeyframe(const Frame& keyframe) {
  if (!attached_.load()) return;
  {
    // A copy (a memcpy of the images, buffers reused): the piece is made on this publisher's
    // thread, not the tracking thread's (0.7 ms a keyframe). The thread wakes for it, so a few
    // are enough; a stalled thread costs at most this many images.
    constexpr std::size_t kMaxQueued = 8;
    std::unique_lock<std::mutex> lock(incoming_mutex_);
    if (options_.lossless)
      room_.wait(lock, [&] { return incoming_.size() < kMaxQueued || !attached_.load(); });
    if (incoming_.size() >= kMaxQueued) {
      spare_.push_back(std::move(incoming_.front()));
      incoming_.pop_front();
      ++pieces_dropped_;
    }
    Frame copy;
    if (!spare_.empty()) {
      copy = std::move(spare_.back());
      spare_.pop_back();
    }
    copyFrame(keyframe, copy);
    incoming_.push_back(std::move(copy));
  }
  wake_.notify_all();
}

void SessionPublisher::takeKeyframes() {
  std::deque<Frame> keyframes;
  {
    std::lock_guard<std::mutex> lock(incoming_mutex_);
    keyframes.swap(incoming_);
  }
  room_.notify_all();
  for (Frame& keyframe : keyframes) stream_->addKeyframe(keyframe);
  std::lock_guard<std::mutex> lock(incoming_mutex_);
  for (Frame& keyframe : keyframes)
    if (spare_.size() < 2) spare_.push_back(std::move(keyframe));
}

void SessionPublisher::send(double now) {
  takeKeyframes();
  if (resend_.exchange(false)) {
    stream_->restart();
    spdlog::info("session stream: sending the session again from its first keyframe");
  }
  for (SessionStream::Record& record : stream_->take(*graph_, now)) {
    std_msgs::UInt8MultiArray msg;
    msg.data.assign(record.bytes.begin(), record.bytes.end());
    switch (record.kind) {
      case SessionStream::Record::Kind::kGraph:
        graph_pub_.publish(msg);
        break;
      case SessionStream::Record::Kind::kPlace:
        places_pub_.publish(msg);
        break;
      case SessionStream::Record::Kind::kPiece:
        pieces_pub_.publish(msg);
        break;
    }
  }
}

void SessionPublisher::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  double next_send = 0.0;
  while (!stop_) {
    const double now = steadySeconds();
    if (graph_ && now >= next_send) {
      send(now);
      next_send = now + options_.interval;
    } else if (graph_) {
      takeKeyframes();  // woken by a keyframe: made a piece now, sent at the next look
    }
    wake_.wait_for(lock, std::chrono::duration<double>(
                             std::max(1e-3, std::min(options_.interval, next_send - now))));
  }
}

}  // namespace rgbdmap
