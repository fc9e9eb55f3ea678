#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/mapping/ground_frame.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"

namespace rgbdmap {

class LoopCloser;
class Mapper;

// The run's counters as they were after a frame (plain values: a subscriber may keep them).
struct PublishedStatus {
  std::uint64_t frames_processed = 0;
  std::uint64_t frames_dropped = 0;
  std::uint64_t keyframes = 0;
  std::uint64_t map_points = 0;
  TrackingState tracking = TrackingState::kNoPose;
  bool keyframe = false;  // this frame was fused into the map
};

// Whoever wants to watch a run (a viewer) subscribes through this interface. Every call comes
// from the mapping thread, so an implementation must return at once: copy what it needs and
// never wait for its consumer.
class MapPublisher {
 public:
  virtual ~MapPublisher() = default;
  // Every frame the mapper took; its images and pose are valid only during the call.
  virtual void publishFrame(const Frame& frame, const PublishedStatus& status) = 0;
  // True when the subscriber has taken the last map and would show a new one.
  virtual bool wantsMap() const = 0;
  virtual void publishMap(std::shared_ptr<const MapCloud> map) = 0;
  // What the map says about up, given just before each map (for a subscriber that draws an
  // occupancy grid from it); most subscribers ignore it.
  virtual void publishUp(const UpEvidence& /*evidence*/) {}
  // The run's loop closer, once made (for a subscriber that streams the session as it grows:
  // it reads it on its own thread through LoopCloser::readGraph()), and null before it goes; a
  // subscriber must stop reading it before returning from the null call.
  virtual void attachGraph(const LoopCloser* /*graph*/, const CameraIntrinsics& /*camera*/) {}
  // Each keyframe given to the map, with its pose as tracked (odometry) and its anchor, before
  // loop closure corrects it (for a subscriber that sends the map as keyframes); valid only
  // during the call.
  virtual void publishKeyframe(const Frame& /*keyframe*/) {}
};

// Attaches the loop closer to a publisher for as long as it lives (declared after it, so that
// the publisher lets go first, on every way out of the run).
class GraphAttachment {
 public:
  GraphAttachment(MapPublisher* publisher, const LoopCloser* graph, const CameraIntrinsics& camera)
      : publisher_(graph ? publisher : nullptr), camera_(camera) {
    if (publisher_) publisher_->attachGraph(graph, camera_);
  }
  ~GraphAttachment() { release(); }
  GraphAttachment(const GraphAttachment&) = delete;
  GraphAttachment& operator=(const GraphAttachment&) = delete;
  void release() {
    if (publisher_) publisher_->attachGraph(nullptr, camera_);
    publisher_ = nullptr;
  }

 private:
  MapPublisher* publisher_;
  CameraIntrinsics camera_;
};

// Feeds a publisher (or nothing, when it is null). Frames are published from the tracking
// thread; map snapshots are extracted on the fusion thread (which owns the map) when the
// tracking thread finds one due. Extracting costs time proportional to the map, so snapshots are
// spaced to keep that cost under `max_share` of the time, and at least `min_interval` seconds
// apart.
class MapPublication {
 public:
  explicit MapPublication(MapPublisher* publisher, double min_interval = 0.5,
                          double max_share = 0.05)
      : publisher_(publisher), min_interval_(min_interval), max_share_(max_share) {}

  // Tracking thread: every frame, after its pose and keyframe decision.
  void afterFrame(const Frame& frame, TrackingState state, const RunStats& stats, bool keyframe);
  // A keyframe the map took, its pose as tracked.
  void afterKeyframe(const Frame& keyframe) {
    if (publisher_) publisher_->publishKeyframe(keyframe);
  }
  // Tracking thread: whether to ask the fusion thread for a map now (at most once per new
  // keyframe, when the subscriber is ready and the spacing allows).
  bool mapDue(const RunStats& stats);
  // Fusion thread: extracts the map and publishes it.
  void publishMap(const Mapper& mapper);
  // The final map, already extracted for the final save.
  void atEnd(std::shared_ptr<const MapCloud> map, const UpEvidence& up);

 private:
  MapPublisher* publisher_;
  double min_interval_;
  double max_share_;
  std::atomic<double> next_map_at_{0.0};  // steady-clock seconds; written by the fusion thread
  std::uint64_t keyframes_published_ = 0;
};

}  // namespace rgbdmap
