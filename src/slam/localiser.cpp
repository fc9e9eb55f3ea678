#include "rgbdmap/slam/localiser.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "rgbdmap/base/thread_name.hpp"
#include "rgbdmap/slam/motion.hpp"

namespace rgbdmap {
namespace {

// Keyframes that may wait in a replay (each holds its full-resolution images).
constexpr std::size_t kMaxQueued = 2;
// Nearest saved keyframes by pose compared by appearance, per keyframe, once placed.
constexpr std::size_t kMaxCompared = 20;
// After this many metres walked without a placement, the search covers the whole saved map
// again (the estimate may have drifted beyond the nearby places).
constexpr double kLostAfterMetres = 3.0;

}  // namespace

Localiser::Localiser(const LoopCloser::Saved& saved, const CameraIntrinsics& camera,
                     const TrackingOptions& tracking, const LoopOptions& loop, double min_depth,
                     double max_depth, PoseCorrections& corrections, RunStats& stats, bool lossless)
    : options_(loop),
      corrections_(corrections),
      stats_(stats),
      lossless_(lossless),
      recognition_(camera, tracking, loop, min_depth, max_depth) {
  for (std::size_t id = 0; id < saved.keyframes.size(); ++id) {
    saved_poses_.push_back(saved.keyframes[id].pose);
    if (id < saved.places.size() && saved.places[id]) {
      recognition_.restore(static_cast<int>(id), saved.places[id]);
      place_ids_.push_back(static_cast<int>(id));
    }
  }
  stats_.place_bytes.store(recognition_.memoryBytes(), std::memory_order_relaxed);
  thread_ = std::thread([this] { run(); });
}

Localiser::~Localiser() { finish(); }

void Localiser::addKeyframe(TrackedKeyframe keyframe) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (lossless_) {
    changed_.wait(lock, [&] { return queue_.size() < kMaxQueued; });
  } else {
    // Behind a live camera: only the newest keyframe is worth looking for.
    while (!queue_.empty()) {
      queue_.pop_front();
      ++counts_.skipped;
    }
  }
  queue_.push_back(std::move(keyframe));
  changed_.notify_all();
}

void Localiser::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finishing_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

Localiser::Counts Localiser::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

void Localiser::run() {
  nameThisThread("rgbdmap-locate");
  giveWayToTracking();
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
    try {
      process(keyframe);
    } catch (const std::exception& e) {
      // A keyframe that cannot be looked for leaves the run where it was placed.
      spdlog::warn("localisation: keyframe {} not looked for: {}", keyframe.id, e.what());
    }
  }
}

void Localiser::process(TrackedKeyframe& keyframe) {
  if (last_odometry_) {
    const Eigen::Isometry3d step = last_odometry_->inverse() * keyframe.pose;
    walked_ += pathLength(step);
  }
  last_odometry_ = keyframe.pose;
  if (keyframe.color.empty() || keyframe.depth.empty()) return;

  // The keyframe goes in after the saved places, is looked for, and goes again.
  const auto slot = static_cast<int>(saved_poses_.size());
  TrackedKeyframe query;
  query.id = static_cast<std::uint64_t>(slot);
  query.timestamp = keyframe.timestamp;
  query.color = keyframe.color;
  query.depth = keyframe.depth;
  recognition_.add(query);
  PlaceRecognition::Counts found_counts;
  const std::optional<LoopMeasurement> found =
      recognition_.find(candidatesFor(keyframe.pose, walked_), found_counts);
  recognition_.forget(slot);
  stats_.keyframes_looked_for.fetch_add(1, std::memory_order_relaxed);

  if (found) {
    Placement placement;
    placement.keyframe = keyframe.id;
    placement.timestamp = keyframe.timestamp;
    placement.walked = walked_;
    placement.odometry_in_map =
        frameInSavedMap(saved_poses_[static_cast<std::size_t>(found->earlier)],
                        found->later_in_earlier, keyframe.pose);
    const bool with_current = current_ && agree(*current_, placement);
    const bool with_candidate = candidate_ && agree(*candidate_, placement);
    if (with_current || with_candidate) {
      accept(placement);
      candidate_.reset();
    } else {
      candidate_ = placement;  // waits for the next placement to agree with it
    }
  }
  // Every keyframe from here on carries the placement in use (as tracked live).
  if (current_ && table_.size() <= keyframe.id) {
    table_.resize(keyframe.id + 1, current_->odometry_in_map);
    corrections_.publish(table_);
  }
}

std::vector<int> Localiser::candidatesFor(const Eigen::Isometry3d& odometry, double walked) const {
  if (!current_ || walked - current_->walked > kLostAfterMetres) return place_ids_;
  const Eigen::Isometry3d x = current_->odometry_in_map * odometry;
  const Eigen::Vector3d axis = x.linear().col(2);
  const double allowance = options_.drift_per_metre * (walked - current_->walked);
  std::vector<std::pair<double, int>> near;
  for (const int id : place_ids_) {
    const Eigen::Isometry3d& xj = saved_poses_[static_cast<std::size_t>(id)];
    const double distance = (xj.translation() - x.translation()).norm();
    const double cosine = std::clamp(xj.linear().col(2).dot(axis), -1.0, 1.0);
    if (distance <= options_.search_radius + allowance &&
        std::acos(cosine) <= options_.max_view_angle + allowance)
      near.emplace_back(distance, id);
  }
  std::sort(near.begin(), near.end());
  if (near.size() > kMaxCompared) near.resize(kMaxCompared);
  std::vector<int> ids;
  for (const auto& [distance, id] : near) ids.push_back(id);
  return ids;
}

bool Localiser::agree(const Placement& a, const Placement& b) const {
  return placementsAgree(a.odometry_in_map, b.odometry_in_map, b.walked - a.walked, options_);
}

void Localiser::accept(const Placement& placement) {
  const bool first = !current_;
  if (current_) {
    const Eigen::Isometry3d change =
        current_->odometry_in_map.inverse() * placement.odometry_in_map;
    spdlog::debug("localisation: keyframe {} placed, {:.3f} m and {:.2f} degrees from the last",
                  placement.keyframe, change.translation().norm(),
                  rotationAngle(change) * kDegreesPerRadian);
  }
  current_ = placement;
  if (table_.size() <= placement.keyframe) {
    table_.resize(placement.keyframe + 1, placement.odometry_in_map);
  } else {
    table_[placement.keyframe] = placement.odometry_in_map;
  }
  corrections_.publish(table_);
  stats_.keyframes_placed.fetch_add(1, std::memory_order_relaxed);
  std::lock_guard<std::mutex> lock(mutex_);
  if (first) {
    counts_.first_placed = static_cast<std::int64_t>(placement.keyframe);
    spdlog::info("localisation: placed in the saved map at keyframe {} (t = {:.3f})",
                 placement.keyframe, placement.timestamp);
  }
}

}  // namespace rgbdmap
