#pragma once

#include <ros/ros.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "rgbdmap/sessions/session_stream.hpp"

namespace rgbdmap {

// The session as it grows, for a fleet's merger: ~session/graph, ~session/places and
// ~session/pieces (std_msgs/UInt8MultiArray, each message one SessionStream record), every
// `interval` seconds from a thread of its own, within the stream's byte budget. Mapping never
// waits for it: it reads the graph under the loop closer's lock, as a checkpoint does, and a
// keyframe is copied into a short queue (the oldest dropped when full) for this thread to make
// a map piece of. Lossless (a bag replayed), a full queue is waited for instead: every keyframe
// then becomes a piece, however slow this thread is.
class SessionPublisher {
 public:
  struct Options {
    double interval = 0.5;  // seconds between looks at the graph
    SessionStream::Options stream;
    bool lossless = false;
  };
  SessionPublisher(ros::NodeHandle& private_nh, Options options);
  ~SessionPublisher();

  // The loop closer to stream (null: stop reading it; returns once the thread has let go).
  void attach(const LoopCloser* graph, const CameraIntrinsics& camera);
  // Everything again from the first keyframe (~session/resend: a merger that came late).
  void resend() { resend_.store(true); }
  // A keyframe the map took (tracking thread): copied, made a map piece on this publisher's
  // thread while a graph is attached.
  void addKeyframe(const Frame& keyframe);
  // What went out so far (after the last attach(nullptr): final).
  SessionStream::Totals totals() const;
  // Keyframes dropped from the full queue, never sent (none when lossless).
  std::uint64_t keyframesDropped() const;
  std::uint64_t run() const { return run_; }

 private:
  void loop();
  void send(double now);
  void takeKeyframes();  // the keyframes queued, into the stream

  Options options_;
  std::uint64_t run_;
  ros::Publisher graph_pub_, places_pub_, pieces_pub_;
  // Keyframes copied on the tracking thread, for the stream (their own lock: the tracking thread
  // never waits for a send), and a few buffers to copy into.
  mutable std::mutex incoming_mutex_;
  std::condition_variable room_;  // lossless: the queue has room again (or the graph went)
  std::deque<Frame> incoming_;
  std::vector<Frame> spare_;
  std::uint64_t pieces_dropped_ = 0;
  std::atomic<bool> attached_{false};
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  const LoopCloser* graph_ = nullptr;
  std::unique_ptr<SessionStream> stream_;
  SessionStream::Totals totals_;
  double started_ = 0.0;
  std::atomic<bool> resend_{false};
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace rgbdmap
