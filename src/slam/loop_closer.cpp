#include "rgbdmap/slam/loop_closer.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/base/thread_name.hpp"
#include "rgbdmap/slam/motion.hpp"

namespace rgbdmap {
namespace {

// Keyframes that may wait for the loop thread. Each holds its full-resolution images (~2 MB); the
// thread takes 50 ms (p50) per keyframe and keyframes come every 150 ms or more, so a few do.
constexpr std::size_t kMaxWaitingKeyframes = 4;
constexpr std::size_t kMaxSettled = 64;  // corrections kept for settledAfter()
// Nearest candidates by pose that are compared by appearance, per keyframe.
constexpr std::size_t kMaxComparedByAppearance = 20;
// A loop that moves the newest pose by this much (m, or rad) is worth a log line.
constexpr double kNoticeableShift = 0.01;

}  // namespace

LoopCloser::LoopCloser(const CameraIntrinsics& camera, const TrackingOptions& tracking,
                       const LoopOptions& loop, double min_depth, double max_depth,
                       PoseCorrections& corrections, RunStats& stats, bool lossless,
                       const Saved* continued)
    : options_(loop),
      corrections_(corrections),
      stats_(stats),
      lossless_(lossless),
      places_(camera, tracking, loop, min_depth, max_depth),
      window_(camera, tracking, loop, min_depth, max_depth),
      floor_(camera, min_depth, max_depth, KeyframeFloor::Config{}) {
  if (continued) restore(*continued);
  thread_ = std::thread([this] { run(); });
}

void LoopCloser::restore(const Saved& saved) {
  const auto n = saved.keyframes.size();
  if (n == 0) return;  // nothing to go on from: an ordinary run
  // The path walked, along the odometry edges (a keyframe without one, the first of a part the
  // saved run had not joined yet, goes on from the one before it).
  std::vector<const PoseGraph::Edge*> odometry(n, nullptr);
  for (const PoseGraph::Edge& e : saved.edges) {
    graph_.addEdge(e);
    // The first is the tracker's; window edges from further back come after it.
    if (!e.loop && e.from < e.to && !odometry[static_cast<std::size_t>(e.to)])
      odometry[static_cast<std::size_t>(e.to)] = &e;
  }
  for (std::size_t i = 0; i < n; ++i) {
    Node node;
    node.timestamp = saved.keyframes[i].timestamp;
    node.odometry = saved.keyframes[i].odometry;
    if (const PoseGraph::Edge* e = odometry[i])
      node.walked = nodes_[static_cast<std::size_t>(e->from)].walked + pathLength(e->measurement());
    else if (i > 0)
      node.walked = nodes_.back().walked;
    nodes_.push_back(node);
    graph_.addNode(saved.keyframes[i].pose);
    if (i < saved.places.size() && saved.places[i]) {
      places_.restore(static_cast<int>(i), saved.places[i]);
      saved_places_.push_back(static_cast<int>(i));
    }
  }
  first_own_ = static_cast<int>(n);
  last_closed_ = first_own_ - 1;
  stats_.place_bytes.store(places_.memoryBytes(), std::memory_order_relaxed);
  publish();
}

LoopCloser::~LoopCloser() { finish(); }

void LoopCloser::addKeyframe(TrackedKeyframe keyframe) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (lossless_) {
    changed_.wait(lock, [&] { return queue_.size() < kMaxWaitingKeyframes; });
  } else {
    // Behind a live camera: the oldest waiting keyframe that still has its images joins the
    // graph without a search, not this one. Where the camera is now is where a loop is about to
    // close (a lap's end, seen twice in a row for the loop to be accepted), and the newest
    // keyframes are the ones searched after the camera stops.
    // (Keyframes come one at a time: one gives way at most.)
    const auto has_images = [](const TrackedKeyframe& k) { return !k.color.empty(); };
    if (static_cast<std::size_t>(std::count_if(queue_.begin(), queue_.end(), has_images)) >=
        kMaxWaitingKeyframes) {
      TrackedKeyframe& oldest = *std::find_if(queue_.begin(), queue_.end(), has_images);
      oldest.color.release();
      oldest.depth.release();
      stats_.loop_keyframes_unsearched.fetch_add(1, std::memory_order_relaxed);
    }
  }
  queue_.push_back(std::move(keyframe));
  ++added_;
  changed_.notify_all();
}

void LoopCloser::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finishing_ = true;
  }
  changed_.notify_all();
  if (!thread_.joinable()) return;
  thread_.join();
  spdlog::info("loop closure: {} keyframes, {} loops closed, {} rejected; place database {:.1f} MB",
               nodes_.size(), stats_.loops_accepted.load(), stats_.loops_rejected.load(),
               static_cast<double>(places_.memoryBytes()) / (1024.0 * 1024.0));
}

void LoopCloser::forgetPlaces() {
  for (std::size_t id = 0; id < nodes_.size(); ++id) places_.forget(static_cast<int>(id));
}

LoopCloser::Saved::Keyframe LoopCloser::GraphView::keyframe(std::size_t id) const {
  return {nodes_[id].timestamp, nodes_[id].odometry, graph_.pose(static_cast<int>(id))};
}

void LoopCloser::readGraph(const std::function<void(const GraphView&)>& read) const {
  std::lock_guard<std::mutex> lock(graph_mutex_);
  read(GraphView(nodes_, graph_));
}

void LoopCloser::run() {
  nameThisThread("rgbdmap-loops");
  // Loop closure improves what tracking and fusion do; when two cores are short, they come first.
  giveWayToTracking();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (lossless_) settled_.push_back(corrections_.snapshot());  // before any keyframe
  }
  changed_.notify_all();
  bool failed = false;
  for (;;) {
    TrackedKeyframe keyframe;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [&] { return !queue_.empty() || finishing_; });
      if (queue_.empty()) break;
      keyframe = std::move(queue_.front());
      queue_.pop_front();
    }
    changed_.notify_all();
    const auto start = std::chrono::steady_clock::now();
    try {
      process(keyframe);
    } catch (const std::exception& e) {
      // Loop closure is an improvement, never a reason to stop mapping: say it once, go on.
      if (!failed) spdlog::error("loop closure: keyframe {}: {}", keyframe.id, e.what());
      failed = true;
    }
    stats_.loop_latency.record(secondsSince(start));
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (lossless_) {
        settled_.push_back(corrections_.snapshot());
        // Fusion asks for states a few keyframes old (its slots and this queue bound how far it
        // lags); one that stopped asking (after a failure) must not make them pile up.
        if (settled_.size() > kMaxSettled) letSettledGoBefore(settled_first_ + 1);
      }
    }
    changed_.notify_all();
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ended_ = true;
  }
  changed_.notify_all();
}

std::uint64_t LoopCloser::keyframesAdded() {
  std::lock_guard<std::mutex> lock(mutex_);
  return added_;
}

PoseCorrections::Snapshot LoopCloser::settledAfter(std::uint64_t added) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return settled_first_ + settled_.size() > added || ended_; });
  if (added < settled_first_ || added >= settled_first_ + settled_.size())
    return corrections_.snapshot();  // the thread has stopped (or a state long let go)
  letSettledGoBefore(added);
  return settled_.front();
}

void LoopCloser::letSettledGoBefore(std::uint64_t added) {
  while (settled_first_ < added && !settled_.empty()) {
    settled_.pop_front();
    ++settled_first_;
  }
}

PoseGraph::Edge LoopCloser::edgeOf(int from, int to, const Eigen::Isometry3d& measurement,
                                   const Eigen::Matrix<double, 6, 6>& information,
                                   bool loop) const {
  PoseGraph::Edge edge;
  edge.from = from;
  edge.to = to;
  edge.setMeasurement(measurement);
  edge.loop = loop;
  if (information.allFinite() && information.trace() > 0.0) {
    edge.setSqrtInformation(PoseGraph::sqrtInformation(information * options_.edge_pixels));
  } else {
    // No alignment behind it (a keyframe the tracker could not relate): a weak tie of 10 cm
    // and 0.1 rad, so the graph stays connected without trusting it.
    edge.setSqrtInformation(Eigen::Matrix<double, 6, 6>::Identity() * 10.0);
  }
  return edge;
}

void LoopCloser::process(TrackedKeyframe& keyframe) {
  const int id = static_cast<int>(nodes_.size());
  if (keyframe.id != static_cast<std::uint64_t>(id))
    throw std::logic_error("keyframes out of order: got " + std::to_string(keyframe.id) +
                           ", expected " + std::to_string(id));
  Node node;
  node.timestamp = keyframe.timestamp;
  node.odometry = keyframe.pose;
  std::unique_lock<std::mutex> graph_lock(graph_mutex_);
  if (id == 0 || (id == first_own_ && !joined())) {
    // The world's first keyframe, or this run's first while it is not tied to the saved map:
    // held where odometry put it, so that its part of the graph has a frame of its own.
    graph_.addNode(keyframe.pose);
    if (id > 0) graph_.hold(id, true);
  } else {
    // Tied to the keyframe it was tracked against; a keyframe without one (never, from the
    // dense tracker) is tied to the previous keyframe by odometry, weakly.
    int reference = static_cast<int>(keyframe.reference);
    Eigen::Isometry3d from = keyframe.from_reference;
    Eigen::Matrix<double, 6, 6> information = keyframe.information;
    if (reference < 0 || reference >= id) {
      reference = id - 1;
      from = nodes_.back().odometry.inverse() * keyframe.pose;
      information.setZero();
    }
    graph_.addNode(graph_.pose(reference) * from);
    graph_.addEdge(edgeOf(reference, id, from, information, false));
    node.walked = nodes_[static_cast<std::size_t>(reference)].walked + from.translation().norm() +
                  kMetresPerRadian * rotationAngle(from);
  }
  nodes_.push_back(node);
  graph_lock.unlock();

  places_.add(keyframe);
  const bool floor_seen = observeFloor(id, keyframe.depth);
  tighten(window_.add(keyframe, [this](int k) { return graph_.pose(k); }), floor_seen);
  keyframe.color.release();
  keyframe.depth.release();
  std::vector<LoopMeasurement> accepted;
  const bool was_joined = joined();
  if (!was_joined && places_.described(id)) lookForSavedMap(id);
  if (places_.described(id) && joined() == was_joined) {
    PlaceRecognition::Counts counts;
    const std::optional<LoopMeasurement> loop = places_.find(candidatesFor(id), counts);
    stats_.loop_candidates.fetch_add(static_cast<std::uint64_t>(counts.proposed));
    stats_.loops_verified.fetch_add(static_cast<std::uint64_t>(counts.verified));
    if (loop && !plausible(*loop)) {
      stats_.loops_rejected.fetch_add(1);
      spdlog::debug("loop {} -> {} rejected: a larger correction than drift explains", loop->later,
                    loop->earlier);
    } else if (loop) {
      bool agreed = false;
      for (Pending& p : pending_) {
        if (p.loop.later >= loop->later || !agree(p.loop, *loop)) continue;
        agreed = true;
        if (!p.accepted) {
          accepted.push_back(p.loop);
          p.accepted = true;
        }
      }
      if (agreed) accepted.push_back(*loop);
      pending_.push_back({*loop, agreed});
    }
  }
  // Loops that found no agreement within the window are dropped.
  while (!pending_.empty() && pending_.front().loop.later < id - options_.consistency_keyframes) {
    if (!pending_.front().accepted) stats_.loops_rejected.fetch_add(1);
    pending_.pop_front();
  }
  if (!accepted.empty()) close(accepted);
  if (nearRememberedPlace(id)) places_.forget(id);
  stats_.place_bytes.store(places_.memoryBytes(), std::memory_order_relaxed);
  publish();
}

std::vector<int> LoopCloser::candidatesFor(int id) const {
  const Eigen::Isometry3d x = graph_.pose(id);
  const double walked = nodes_[static_cast<std::size_t>(id)].walked;
  std::vector<std::pair<double, int>> near;
  // Until the run joins a saved map, its own keyframes only: the saved ones are in another frame.
  for (int j = joined() ? 0 : first_own_; j + options_.recent_keyframes < id; ++j) {
    if (!places_.described(j)) continue;
    // (A saved keyframe may be further along the path than this run's: its walk came first.)
    const double allowance =
        options_.drift_per_metre * std::abs(walked - nodes_[static_cast<std::size_t>(j)].walked);
    if (const auto distance = loopSearchDistance(x, graph_.pose(j), allowance, options_))
      near.emplace_back(*distance, j);
  }
  std::sort(near.begin(), near.end());
  if (near.size() > kMaxComparedByAppearance) near.resize(kMaxComparedByAppearance);
  std::vector<int> ids;
  for (const auto& n : near) ids.push_back(n.second);
  return ids;
}

bool LoopCloser::nearRememberedPlace(int id) const {
  const Eigen::Isometry3d x = graph_.pose(id);
  for (int j = joined() ? 0 : first_own_; j < id; ++j) {
    if (!places_.described(j)) continue;
    const Eigen::Isometry3d relative = graph_.pose(j).inverse() * x;
    if (relative.translation().norm() < options_.place_spacing &&
        rotationAngle(relative) < options_.place_spacing_angle)
      return true;
  }
  return false;
}

Eigen::Isometry3d LoopCloser::impliedPose(const LoopMeasurement& loop) const {
  return graph_.pose(loop.earlier) * loop.later_in_earlier;
}

bool LoopCloser::plausible(const LoopMeasurement& loop) const {
  const Eigen::Isometry3d correction = graph_.pose(loop.later).inverse() * impliedPose(loop);
  const double walked = std::abs(nodes_[static_cast<std::size_t>(loop.later)].walked -
                                 nodes_[static_cast<std::size_t>(loop.earlier)].walked);
  const double allowance = kBaseDriftAllowance + options_.drift_per_metre * walked;
  return correction.translation().norm() <= allowance && rotationAngle(correction) <= allowance;
}

bool LoopCloser::agree(const LoopMeasurement& a, const LoopMeasurement& b) const {
  if (b.later - a.later > options_.consistency_keyframes) return false;
  // Where each loop would put keyframe b.later: a's correction (the rigid motion that moves
  // a.later to where a says) applied to b.later's estimate, and b's own.
  const Eigen::Isometry3d moved_by_a =
      impliedPose(a) * graph_.pose(a.later).inverse() * graph_.pose(b.later);
  const Eigen::Isometry3d difference = moved_by_a.inverse() * impliedPose(b);
  return difference.translation().norm() <= options_.consistent_translation &&
         rotationAngle(difference) <= options_.consistent_rotation;
}

void LoopCloser::close(const std::vector<LoopMeasurement>& loops) {
  // Since the last loop closed, with a margin: what odometry alone has carried since (the whole
  // graph until the first loop).
  const int window = options_.optimise_window;
  const int first_free =
      last_closed_ < 0 ? 0 : std::max(0, std::min(graph_.size() - window, last_closed_ - window));
  std::unique_lock<std::mutex> graph_lock(graph_mutex_);
  const PoseGraph::Checkpoint before = graph_.checkpoint(first_free);
  const Eigen::Isometry3d newest_before = graph_.pose(graph_.size() - 1);
  for (const LoopMeasurement& loop : loops)
    graph_.addEdge(edgeOf(loop.earlier, loop.later, loop.later_in_earlier, loop.information, true));
  const PoseGraph::Summary summary = graph_.optimise(100, first_free);
  stats_.optimise_latency.record(summary.seconds);
  bool consistent = summary.usable;
  const double worst = graph_.worstWhitenedError(loops.size());
  consistent = consistent && worst <= options_.max_loop_residual;
  if (!consistent) {
    // The rest of the graph disagrees with these loops: not the same place after all.
    graph_.rollBack(before);
    graph_lock.unlock();
    stats_.loops_rejected.fetch_add(loops.size());
    spdlog::debug("{} loop(s) at keyframe {} rejected after optimising (residual {:.2f})",
                  loops.size(), loops.back().later, worst);
    return;
  }
  graph_lock.unlock();
  stats_.loops_accepted.fetch_add(loops.size());
  const Eigen::Isometry3d moved = newest_before.inverse() * graph_.pose(graph_.size() - 1);
  const LoopMeasurement& last = loops.back();
  // While the camera goes over old ground every keyframe closes a loop; say so when a revisit
  // starts or a loop moves the camera noticeably, and count the rest (stats, status line).
  const bool revisit =
      last_closed_ < 0 || last.later - last_closed_ > options_.consistency_keyframes;
  last_closed_ = last.later;
  if (!revisit && moved.translation().norm() < kNoticeableShift &&
      rotationAngle(moved) < kNoticeableShift)
    return;
  const Node& later = nodes_[static_cast<std::size_t>(last.later)];
  const Node& earlier = nodes_[static_cast<std::size_t>(last.earlier)];
  spdlog::info(
      "loop closed: keyframe {} (t {:.6f}) is back at keyframe {} (t {:.6f}, {:.1f} s earlier); "
      "the camera's pose moved {:.1f} cm, {:.1f} deg ({} keyframes optimised in {:.0f} ms)",
      last.later, later.timestamp, last.earlier, earlier.timestamp,
      later.timestamp - earlier.timestamp, 100.0 * moved.translation().norm(),
      rotationAngle(moved) * kDegreesPerRadian, graph_.size() - first_free, summary.seconds * 1e3);
}

bool LoopCloser::observeFloor(int id, const cv::Mat& depth) {
  // Before the run joins a saved map its keyframes are in a frame of their own.
  if (!options_.floor || !joined()) return false;
  const Eigen::Isometry3d pose = graph_.pose(id);
  std::optional<CameraPlane> seen;
  if (graph_.hasWorldPlane()) {
    const Eigen::Vector3d n = graph_.worldPlaneNormal();
    CameraPlane guess;
    guess.normal = pose.linear().transpose() * n;
    guess.distance = graph_.worldPlaneDistance() - n.dot(pose.translation());
    seen = floor_.near(depth, guess);
  } else {
    // The world's frame is its first camera's, held roughly upright: up is about -y.
    seen = floor_.discover(depth, pose.linear().transpose() * -Eigen::Vector3d::UnitY());
  }
  if (!seen) return false;
  std::lock_guard<std::mutex> graph_lock(graph_mutex_);
  if (!graph_.hasWorldPlane()) {
    const Eigen::Vector3d n = pose.linear() * seen->normal;
    graph_.setWorldPlane(n, seen->distance + n.dot(pose.translation()));
    spdlog::info("floor: found {:.2f} m below keyframe {}; keyframes that see it are tied to it",
                 -seen->distance, id);
  }
  PoseGraph::PlaneObservation o;
  o.node = id;
  for (int i = 0; i < 3; ++i) o.normal[i] = static_cast<float>(seen->normal[i]);
  o.distance = static_cast<float>(seen->distance);
  // A narrow strip of floor (a view along a wall) measures its tilt across itself less well.
  constexpr double kFullExtent = 0.3;  // m, where the tilt is as good as a fit gets
  o.sigma_normal =
      static_cast<float>(options_.floor_sigma_tilt * std::max(1.0, kFullExtent / seen->extent));
  o.sigma_distance = static_cast<float>(options_.floor_sigma_height);
  graph_.addPlaneObservation(o);
  stats_.floor_observations.fetch_add(1, std::memory_order_relaxed);
  return true;
}

void LoopCloser::tighten(const std::vector<LoopMeasurement>& local, bool floor_seen) {
  if (local.empty() && !floor_seen) return;
  const int first_free =
      std::max(graph_.size() - options_.window_optimise, joined() ? 0 : first_own_);
  std::lock_guard<std::mutex> graph_lock(graph_mutex_);
  const PoseGraph::Checkpoint before = graph_.checkpoint(first_free);
  for (const LoopMeasurement& m : local) {
    const Eigen::Isometry3d change =
        (graph_.pose(m.earlier).inverse() * graph_.pose(m.later)).inverse() * m.later_in_earlier;
    spdlog::debug("window: keyframe {} -> {}: {:.1f} mm, {:.2f} deg from the graph, overlap {:.2f}",
                  m.later, m.earlier, 1000.0 * change.translation().norm(),
                  rotationAngle(change) * kDegreesPerRadian, m.overlap);
    graph_.addEdge(edgeOf(m.earlier, m.later, m.later_in_earlier, m.information, false));
  }
  const PoseGraph::Summary summary = graph_.optimise(20, first_free);
  stats_.optimise_latency.record(summary.seconds);
  if (!summary.usable) graph_.rollBack(before);
}

void LoopCloser::publish() {
  PoseCorrections::Table table(nodes_.size());
  for (std::size_t i = 0; i < nodes_.size(); ++i)
    table[i] = graph_.pose(static_cast<int>(i)) * nodes_[i].odometry.inverse();
  corrections_.publish(std::move(table), first_own_, joined());
}

void LoopCloser::lookForSavedMap(int id) {
  PlaceRecognition::Counts counts;
  const std::optional<LoopMeasurement> found = places_.find(saved_places_, counts);
  stats_.keyframes_looked_for.fetch_add(1, std::memory_order_relaxed);
  if (!found) return;
  Placement placement;
  placement.loop = *found;
  placement.own_in_saved =
      frameInSavedMap(graph_.pose(found->earlier), found->later_in_earlier, graph_.pose(id));
  stats_.keyframes_placed.fetch_add(1, std::memory_order_relaxed);
  // A place that looks alike elsewhere rarely passes twice: the first placement waits for the
  // next one, which must put the run's frame in the same place, give or take the odometry's drift
  // between the two keyframes.
  if (placement_ && id - placement_->loop.later <= options_.consistency_keyframes) {
    const double walked = nodes_[static_cast<std::size_t>(id)].walked -
                          nodes_[static_cast<std::size_t>(placement_->loop.later)].walked;
    if (placementsAgree(placement_->own_in_saved, placement.own_in_saved, walked, options_) &&
        join(*placement_, placement))
      return;
  }
  placement_ = placement;
}

bool LoopCloser::join(const Placement& first, const Placement& second) {
  std::unique_lock<std::mutex> graph_lock(graph_mutex_);
  const PoseGraph::Checkpoint before = graph_.checkpoint(0);
  // The run's part moved rigidly into the saved frame, then let go: from here on one graph,
  // optimised whole with only the saved run's first keyframe held, as one run over both would
  // be. The saved keyframes move too when the new loops say so: holding them would keep the
  // saved run's drift in the map for good.
  for (int i = first_own_; i < graph_.size(); ++i)
    graph_.setPose(i, second.own_in_saved * graph_.pose(i));
  graph_.hold(first_own_, false);
  for (const Placement* p : {&first, &second})
    graph_.addEdge(edgeOf(p->loop.earlier, p->loop.later, p->loop.later_in_earlier,
                          p->loop.information, true));
  const PoseGraph::Summary summary = graph_.optimise(100, 0);
  stats_.optimise_latency.record(summary.seconds);
  const double worst = graph_.worstWhitenedError(2);
  if (!summary.usable || worst > options_.max_loop_residual) {
    graph_.rollBack(before);
    graph_.hold(first_own_, true);
    stats_.loops_rejected.fetch_add(2);
    spdlog::debug(
        "saved map: placement at keyframes {} and {} rejected after optimising "
        "(residual {:.2f})",
        first.loop.later, second.loop.later, worst);
    return false;
  }
  joined_at_.store(second.loop.later);
  // Drift allowances between the two parts count along the path from where they met.
  const double shift = nodes_[static_cast<std::size_t>(second.loop.earlier)].walked -
                       nodes_[static_cast<std::size_t>(second.loop.later)].walked;
  for (std::size_t i = static_cast<std::size_t>(first_own_); i < nodes_.size(); ++i)
    nodes_[i].walked += shift;
  graph_lock.unlock();
  last_closed_ = second.loop.later;
  placement_.reset();
  pending_.clear();  // loops of the run's own frame, before it moved
  stats_.loops_accepted.fetch_add(2);
  const Node& own = nodes_[static_cast<std::size_t>(second.loop.later)];
  const Node& saved = nodes_[static_cast<std::size_t>(second.loop.earlier)];
  spdlog::info(
      "continuing: keyframe {} (t {:.6f}) recognised saved keyframe {} (t {:.6f}), as keyframe "
      "{} did: the run's {} keyframes so far joined the saved map's frame ({} ms)",
      second.loop.later, own.timestamp, second.loop.earlier, saved.timestamp, first.loop.later,
      graph_.size() - first_own_, static_cast<int>(summary.seconds * 1e3));
  return true;
}

}  // namespace rgbdmap
