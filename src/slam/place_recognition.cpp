#include "rgbdmap/slam/place_recognition.hpp"

#include <algorithm>

#include "rgbdmap/slam/motion.hpp"

namespace rgbdmap {

TrackingOptions loopVerificationOptions(const TrackingOptions& tracking, const LoopOptions& loop) {
  TrackingOptions o = tracking;
  o.finest_level = std::min(loop.finest_level, o.coarsest_level);
  o.depth_weight = loop.depth_weight;
  return o;
}

std::optional<LoopMeasurement> verifiedLoop(const AlignmentResult& dense,
                                            const Eigen::Isometry3d& by_features,
                                            const TrackingOptions& verification,
                                            const LoopOptions& loop) {
  if (!dense.finite || dense.overlap < loop.min_overlap ||
      dense.intensity_sigma > verification.max_residual)
    return std::nullopt;
  const Eigen::Isometry3d change = by_features.inverse() * dense.motion;
  if (change.translation().norm() > loop.max_disagreement_translation ||
      rotationAngle(change) > loop.max_disagreement_rotation ||
      dense.motion.translation().norm() > loop.max_distance)
    return std::nullopt;
  return measurementOf(dense);
}

LoopMeasurement measurementOf(const AlignmentResult& dense) {
  LoopMeasurement measured;
  Eigen::Isometry3d relative = dense.motion.inverse();
  relative.linear() = Eigen::Quaterniond(relative.linear()).normalized().toRotationMatrix();
  measured.later_in_earlier = relative;
  measured.information = dense.information;
  measured.overlap = dense.overlap;
  return measured;
}

PlaceRecognition::PlaceRecognition(const CameraIntrinsics& camera, const TrackingOptions& tracking,
                                   const LoopOptions& loop, double min_depth, double max_depth)
    : camera_(camera),
      tracking_(loopVerificationOptions(tracking, loop)),
      options_(loop),
      min_depth_(static_cast<float>(min_depth)),
      max_depth_(static_cast<float>(max_depth)),
      features_(camera, loop.min_inliers, min_depth_, max_depth_),
      aligner_(tracking_) {}

bool PlaceRecognition::described(int id) const {
  return id >= 0 && id < static_cast<int>(entries_.size()) &&
         entries_[static_cast<std::size_t>(id)] != nullptr;
}

void PlaceRecognition::forget(int id) {
  if (!described(id)) return;
  std::lock_guard<std::mutex> lock(entries_mutex_);
  entries_[static_cast<std::size_t>(id)].reset();
}

void PlaceRecognition::add(const TrackedKeyframe& keyframe) {
  const auto id = static_cast<std::size_t>(keyframe.id);
  if (entries_.size() <= id) {
    std::lock_guard<std::mutex> lock(entries_mutex_);
    entries_.resize(id + 1);
  }
  if (keyframe.color.empty() || keyframe.depth.empty()) return;  // nothing to recognise it by
  auto place = std::make_shared<Place>();
  Place& entry = *place;
  const Frame frame = keyframe.frame();
  pyramid_.build(frame, camera_, tracking_.coarsest_level + 1, tracking_.finest_level,
                 tracking_.undistort, min_depth_, max_depth_);
  reference_.build(pyramid_, tracking_.finest_level, tracking_.coarsest_level,
                   static_cast<float>(tracking_.min_gradient));
  entry.reference = PackedReference::pack(reference_);
  features_.prepare(frame);
  features_.describePrepared(keyframe.depth, entry.view);
  std::lock_guard<std::mutex> lock(entries_mutex_);
  entries_[id] = std::move(place);
}

void PlaceRecognition::restore(int id, std::shared_ptr<const Place> place) {
  const auto slot = static_cast<std::size_t>(id);
  std::lock_guard<std::mutex> lock(entries_mutex_);
  if (entries_.size() <= slot) entries_.resize(slot + 1);
  entries_[slot] = std::move(place);
}

std::optional<LoopMeasurement> PlaceRecognition::find(const std::vector<int>& candidates,
                                                      Counts& counts) {
  if (entries_.empty() || !entries_.back()) return std::nullopt;
  const int newest = static_cast<int>(entries_.size()) - 1;
  // Appearance first: how many distinctive ORB matches each candidate shares with the newest.
  std::vector<std::pair<int, int>> ranked;  // (matches, id)
  for (const int id : candidates) {
    if (!described(id)) continue;
    const int matches = features_.similarity(entries_[static_cast<std::size_t>(id)]->view);
    if (matches >= options_.min_matches) ranked.emplace_back(matches, id);
  }
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  if (static_cast<int>(ranked.size()) > options_.max_candidates)
    ranked.resize(static_cast<std::size_t>(options_.max_candidates));

  for (const auto& [matches, id] : ranked) {
    ++counts.proposed;
    const Place& earlier = *entries_[static_cast<std::size_t>(id)];
    int inliers = 0;
    const std::optional<Eigen::Isometry3d> found = features_.locate(earlier.view, &inliers);
    // Only places the camera has really been back to: two views of one wall from a metre apart
    // are not a loop, even when they agree.
    if (!found || found->translation().norm() > options_.max_distance) continue;
    earlier.reference.expand(reference_);
    std::optional<LoopMeasurement> loop =
        verifiedLoop(aligner_.align(reference_, pyramid_, *found), *found, tracking_, options_);
    if (!loop) continue;
    ++counts.verified;
    loop->earlier = id;
    loop->later = newest;
    loop->matches = matches;
    loop->inliers = inliers;
    return loop;
  }
  return std::nullopt;
}

std::size_t PlaceRecognition::memoryBytes() const {
  std::size_t bytes = entries_.capacity() * sizeof(entries_[0]);
  for (const auto& entry : entries_) {
    if (!entry) continue;
    const Place& e = *entry;
    bytes += sizeof(Place) + e.view.descriptors.total() * e.view.descriptors.elemSize();
    bytes += e.view.points.size() * sizeof(cv::Point3f);
    bytes += e.reference.memoryBytes();
  }
  return bytes;
}

std::vector<std::shared_ptr<const PlaceRecognition::Place>> PlaceRecognition::places() const {
  std::lock_guard<std::mutex> lock(entries_mutex_);
  return {entries_.begin(), entries_.end()};
}

}  // namespace rgbdmap
