#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/slam/keyframe_floor.hpp"
#include "rgbdmap/slam/keyframe_window.hpp"
#include "rgbdmap/slam/place_recognition.hpp"
#include "rgbdmap/slam/pose_graph.hpp"
#include "rgbdmap/tracking/keyframe_sink.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {

// Keeps the tracker's keyframes consistent over time, on its own thread: each keyframe becomes a
// pose graph node tied to the keyframe it was tracked against; place recognition looks for an
// earlier keyframe the camera is back at; a verified loop is accepted once a second one from a
// nearby keyframe agrees with it (and it stays agreeable after optimising); then the graph is
// optimised and the corrections published for the map and the trajectories. Tracking never
// waits for it, except in a lossless replay when more than a few keyframes are queued (so that
// a replay gives the same map every time).
class LoopCloser : public KeyframeSink {
  struct Node;  // a keyframe in the graph (below)

 public:
  // What a session saved keeps of loop closure: every keyframe with its odometry and optimised
  // pose, the graph's edges, and the places (by keyframe id, null where none; shared).
  struct Saved {
    struct Keyframe {
      double timestamp = 0.0;
      Eigen::Isometry3d odometry = Eigen::Isometry3d::Identity();
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    };
    std::vector<Keyframe> keyframes;
    std::vector<PoseGraph::Edge> edges;
    std::vector<std::shared_ptr<const PlaceRecognition::Place>> places;
  };

  // lossless: block addKeyframe() while the queue is full instead of skipping the search.
  // The first five as PlaceRecognition's.
  // `continued`: a saved session's graph and places to go on from (--continue). The tracker's
  // keyframes then take ids after the saved ones (firstKeyframeId()) and form a graph of their
  // own, in the run's own frame, until one of them is recognised among the saved places and a
  // second one agrees: then the run's part is moved into the saved map's frame, tied to it by
  // those two loops, and from there on it is one graph (see joinedAt()).
  LoopCloser(const CameraIntrinsics& camera, const TrackingOptions& tracking,
             const LoopOptions& loop, double min_depth, double max_depth,
             PoseCorrections& corrections, RunStats& stats, bool lossless,
             const Saved* continued = nullptr);
  ~LoopCloser() override;
  // The graph as it is, seen under its lock (GraphView is only made by readGraph()).
  class GraphView {
   public:
    std::size_t keyframes() const { return nodes_.size(); }
    Saved::Keyframe keyframe(std::size_t id) const;
    const std::deque<PoseGraph::Edge>& edges() const { return graph_.edges(); }

   private:
    friend class LoopCloser;
    GraphView(const std::vector<LoopCloser::Node>& nodes, const PoseGraph& graph)
        : nodes_(nodes), graph_(graph) {}
    const std::vector<LoopCloser::Node>& nodes_;
    const PoseGraph& graph_;
  };

  void addKeyframe(TrackedKeyframe keyframe) override;
  std::uint64_t firstKeyframeId() const override { return static_cast<std::uint64_t>(first_own_); }
  // Processes every queued keyframe, then stops the thread. The corrections are final after it.
  void finish();
  // How many keyframes addKeyframe() has been given so far.
  std::uint64_t keyframesAdded();
  // The corrections as they were once the first `added` keyframes had been taken into the graph
  // (their window, loops and corrections published), waiting for that if need be: what a
  // lossless replay fuses a keyframe at, so that its map does not depend on how far the loop
  // thread had got. Asked in increasing order (older states are let go); from any thread.
  PoseCorrections::Snapshot settledAfter(std::uint64_t added);
  // Calls `read` with the graph as it is now, from any thread: the loop thread waits while it
  // runs, and it waits at most for one optimisation. A session streams the graph to its file
  // this way (a copy of a long run's graph is megabytes, at every checkpoint).
  void readGraph(const std::function<void(const GraphView&)>& read) const;
  // The places by keyframe id (null where none; shared), at most one a keyframe of the graph
  // as it was when readGraph() last returned or later.
  std::vector<std::shared_ptr<const PlaceRecognition::Place>> places() const {
    return places_.places();
  }
  // Lets the places go (after finish() and the last save: no keyframe comes any more).
  void forgetPlaces();
  // Continuing a saved session: the keyframe at which the run joined the saved map (-1: not
  // yet, or never); after finish(), final.
  std::int64_t joinedAt() const { return joined_at_.load(); }

 private:
  struct Node {
    double timestamp = 0.0;
    double walked = 0.0;  // metres along the odometry path from the first keyframe
    Eigen::Isometry3d odometry = Eigen::Isometry3d::Identity();
  };
  struct Pending {  // a verified loop waiting for a second one to agree
    LoopMeasurement loop;
    bool accepted = false;
  };
  struct Placement {  // where a saved keyframe says the run's own frame lies in the saved map's
    LoopMeasurement loop;
    Eigen::Isometry3d own_in_saved = Eigen::Isometry3d::Identity();
  };

  void run();
  void restore(const Saved& saved);
  void process(TrackedKeyframe& keyframe);
  // Continuing, not joined yet: looks for keyframe `id` among the saved places; joins the saved
  // map once two placements agree.
  void lookForSavedMap(int id);
  bool join(const Placement& first, const Placement& second);
  // One graph in one frame: an ordinary run, or a continued one that has joined the saved map.
  bool joined() const { return first_own_ == 0 || joined_at_.load() >= 0; }
  std::vector<int> candidatesFor(int id) const;
  // Whether an earlier keyframe kept as a place is within loop.place_spacing of `id`.
  bool nearRememberedPlace(int id) const;
  // The pose of `later` the loop implies, with the graph's current estimate of `earlier`.
  Eigen::Isometry3d impliedPose(const LoopMeasurement& loop) const;
  bool plausible(const LoopMeasurement& loop) const;
  bool agree(const LoopMeasurement& a, const LoopMeasurement& b) const;
  void close(const std::vector<LoopMeasurement>& loops);
  // Ties keyframe `id` to the world floor when its depth shows the floor (loop.floor); the first
  // floor seen becomes the world's. Whether it did.
  bool observeFloor(int id, const cv::Mat& depth);
  // The newest keyframe's window alignments as edges, and the newest keyframes optimised (also
  // when only its floor was added).
  void tighten(const std::vector<LoopMeasurement>& local, bool floor_seen);
  void publish();
  PoseGraph::Edge edgeOf(int from, int to, const Eigen::Isometry3d& measurement,
                         const Eigen::Matrix<double, 6, 6>& information, bool loop) const;

  LoopOptions options_;
  PoseCorrections& corrections_;
  RunStats& stats_;
  bool lossless_;
  PlaceRecognition places_;
  KeyframeWindow window_;
  KeyframeFloor floor_;
  // Changed on the loop thread only, under `graph_mutex_` so that readGraph() sees them whole.
  PoseGraph graph_;
  std::vector<Node> nodes_;
  mutable std::mutex graph_mutex_;
  std::deque<Pending> pending_;
  int last_closed_ = -1;  // the newest keyframe of the last loop closed
  // Continuing: the saved keyframes are 0..first_own_-1; until joined, the run's own part is
  // held at its first keyframe, and only the saved places are searched for it.
  int first_own_ = 0;
  std::vector<int> saved_places_;
  std::optional<Placement> placement_;  // waiting for a second that agrees
  std::atomic<std::int64_t> joined_at_{-1};

  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<TrackedKeyframe> queue_;
  bool finishing_ = false;
  bool ended_ = false;  // the loop thread has stopped
  std::uint64_t added_ = 0;
  // Lossless only: settled_[i], the corrections once settled_first_ + i keyframes had been
  // processed (as many as the fusion thread is behind the loop thread, at most kMaxSettled;
  // live, none is kept).
  std::deque<PoseCorrections::Snapshot> settled_;
  std::uint64_t settled_first_ = 0;
  void letSettledGoBefore(std::uint64_t added);  // under mutex_
  std::thread thread_;
};

}  // namespace rgbdmap
