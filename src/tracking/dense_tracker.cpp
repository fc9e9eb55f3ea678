#include "rgbdmap/tracking/dense_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rgbdmap/base/image_buffer_pool.hpp"

namespace rgbdmap {
namespace {

double angle(const Eigen::Isometry3d& t) { return Eigen::AngleAxisd(t.linear()).angle(); }

// The motion t scaled to a fraction s of itself (rotation angle and translation), e.g. the
// per-frame share of a motion over several frame periods.
Eigen::Isometry3d scaled(const Eigen::Isometry3d& t, double s) {
  const Eigen::AngleAxisd aa(t.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(aa.angle() * s, aa.axis()).toRotationMatrix();
  out.translation() = t.translation() * s;
  return out;
}

// The rotation part re-orthonormalised, so rounding never accumulates into a non-rigid pose.
Eigen::Isometry3d rigid(const Eigen::Isometry3d& t) {
  Eigen::Isometry3d out = t;
  out.linear() = Eigen::Quaterniond(t.linear()).normalized().toRotationMatrix();
  return out;
}

}  // namespace

DenseTracker::DenseTracker(const CameraIntrinsics& camera, const TrackingOptions& options,
                           float min_depth, float max_depth, KeyframeSink* sink)
    : camera_(camera),
      options_(options),
      min_depth_(min_depth),
      max_depth_(max_depth),
      aligner_(options),
      relocaliser_(camera, options.relocalisation_min_inliers, min_depth, max_depth),
      sink_(sink),
      readout_(options.readout),
      readout_mean_(options.readout),
      readout_weight_(options.readout_prior_weight),
      first_id_(sink ? sink->firstKeyframeId() : 0),
      next_id_(first_id_) {
  // The images a keyframe keeps (relocalisation's grey and depth while it is among the recent
  // ones, the sink's colour and depth until the loop thread has seen them) come from pooled
  // buffers, taken now: allocated on a keyframe, they cost more than tracking it.
  const int kept = std::max(1, options.relocalisation_keyframes) + 1;
  const int handed = sink ? 3 : 0;
  ImageBufferPool& pool = imageBufferPool();
  pool.reserve(camera.height, camera.width, CV_8UC1, kept);
  pool.reserve(camera.height, camera.width, CV_32FC1, kept + handed);
  pool.reserve(camera.height, camera.width, CV_8UC3, handed);
}

DenseTracker::~DenseTracker() = default;

std::string DenseTracker::describe() const {
  return "dense RGB-D tracking against keyframes (pyramid levels " +
         std::to_string(options_.coarsest_level) + ".." + std::to_string(options_.finest_level) +
         ")";
}

const char* DenseTracker::reject(const AlignmentResult& result, const Eigen::Isometry3d& pose,
                                 const Eigen::Isometry3d& predicted, double periods,
                                 bool check_jump) const {
  if (!result.finite || !pose.matrix().allFinite()) return "estimate is not finite";
  if ((pose.linear().transpose() * pose.linear() - Eigen::Matrix3d::Identity())
          .cwiseAbs()
          .maxCoeff() > 1e-3)
    return "estimate is not a rigid motion";
  if (result.overlap < options_.min_overlap) return "too little of the keyframe in view";
  if (result.intensity_sigma > options_.max_residual) return "residual too large";
  if (check_jump) {
    const Eigen::Isometry3d jump = predicted.inverse() * pose;
    if (jump.translation().norm() > options_.max_jump_translation * periods ||
        angle(jump) > options_.max_jump_rotation * periods)
      return "jump from the predicted pose";
  }
  return nullptr;
}

void DenseTracker::makeKeyframe(const Frame& frame, const Eigen::Isometry3d& pose,
                                const Keyframe* from, const AlignmentResult& alignment) {
  const ReadoutMotion readout = readoutMotion();
  if (sink_) {  // before `from` may leave the window below
    TrackedKeyframe out;
    out.id = next_id_;
    out.timestamp = frame.timestamp;
    out.pose = pose;
    if (from) {
      out.reference = static_cast<std::int64_t>(from->id);
      out.from_reference = rigid(from->pose.inverse() * pose);
      out.information = alignment.information;
    }
    out.readout = readout;
    out.color = pooledCopy(frame.color);
    out.depth = pooledCopy(frame.depth);
    sink_->addKeyframe(std::move(out));
  }
  auto keyframe = std::make_shared<Keyframe>();
  keyframe->id = next_id_;
  keyframe->reference.build(pyramid_, options_.finest_level, options_.coarsest_level,
                            static_cast<float>(options_.min_gradient), readout);
  keyframe->reference.readout_rate = readoutRate();
  keyframe->pose = pose;
  keyframe->points_as_read = (readout_ > 0 || options_.estimate_readout) && !velocity_measured_;
  relocaliser_.remember(frame, keyframe->view);
  keyframes_.push_back(keyframe);
  while (static_cast<int>(keyframes_.size()) > std::max(1, options_.relocalisation_keyframes))
    keyframes_.pop_front();
  keyframe_ = keyframe;
  ++next_id_;
}

bool DenseTracker::accept(Frame& frame, const Eigen::Isometry3d& pose, TrackingState state) {
  frame.anchor = static_cast<std::int64_t>(keyframe_->id);
  frame.pose = pose;
  frame.has_pose = true;
  last_pose_ = pose;
  state_ = state;
  lost_ = false;
  return true;
}

bool DenseTracker::lose(Frame& frame, const Eigen::Isometry3d& predicted) {
  frame.anchor = keyframe_ ? static_cast<std::int64_t>(keyframe_->id) : -1;
  frame.pose = predicted;
  frame.has_pose = false;
  state_ = TrackingState::kLost;
  lost_ = true;
  return false;
}

bool DenseTracker::estimate(Frame& frame) {
  const int levels = options_.coarsest_level + 1;
  pyramid_.build(frame, camera_, levels, options_.finest_level, options_.undistort, min_depth_,
                 max_depth_);
  const bool enough_depth = pyramid_.depthFraction() >= options_.min_depth_fraction;
  if (!started_) {
    last_timestamp_ = frame.timestamp;
    // Nothing to track against yet: the first frame with depth starts the world frame.
    if (!enough_depth) return lose(frame, Eigen::Isometry3d::Identity());
    started_ = true;
    makeKeyframe(frame, Eigen::Isometry3d::Identity(), nullptr, AlignmentResult{});
    forgetVelocity();
    return accept(frame, Eigen::Isometry3d::Identity(), TrackingState::kTracked);
  }
  // Frame periods since the last frame (more than one when frames were dropped or cut out).
  const double dt = frame.timestamp - last_timestamp_;
  last_timestamp_ = frame.timestamp;
  const double periods = std::clamp(std::round(dt / frame_period_), 1.0, 30.0);
  Eigen::Isometry3d predicted = last_pose_;
  for (int i = 0; i < static_cast<int>(periods); ++i) predicted = predicted * velocity_;
  predicted = rigid(predicted);

  aligner_.setReadoutMotion(readoutMotion());
  aligner_.setReadoutRate(options_.estimate_readout ? readoutRate() : ReadoutMotion::Zero());
  if (lost_) {
    Eigen::Isometry3d pose;
    if (!enough_depth || !relocalise(frame, pose)) return lose(frame, last_pose_);
    forgetVelocity();
    return accept(frame, pose, TrackingState::kRelocalised);
  }

  last_result_ =
      aligner_.align(keyframe_->reference, pyramid_, rigid(predicted.inverse() * keyframe_->pose));
  const Eigen::Isometry3d pose = rigid(keyframe_->pose * last_result_.motion.inverse());
  if (reject(last_result_, pose, predicted, periods, true)) {
    forgetVelocity();
    return lose(frame, predicted);
  }
  measureReadout();
  velocity_ = scaled(last_pose_.inverse() * pose, 1.0 / periods);
  velocity_measured_ = true;
  if (!enough_depth) {
    // The image tracks but the frame has (almost) no depth: nothing to map. Its pose is good, so
    // tracking goes on from it, but the next good frame reports the recovery.
    last_pose_ = pose;
    return lose(frame, pose);
  }
  accept(frame, pose, TrackingState::kTracked);
  const Eigen::Isometry3d from_keyframe = keyframe_->pose.inverse() * pose;
  if (from_keyframe.translation().norm() > options_.keyframe_translation ||
      angle(from_keyframe) > options_.keyframe_rotation ||
      last_result_.overlap < options_.keyframe_min_overlap || keyframe_->points_as_read)
    makeKeyframe(frame, pose, keyframe_.get(), last_result_);
  return true;
}

void DenseTracker::forgetVelocity() {
  velocity_.setIdentity();
  velocity_measured_ = false;
}

ReadoutMotion DenseTracker::readoutRate() const {
  ReadoutMotion rate;
  const Eigen::AngleAxisd turn(velocity_.linear());
  rate.head<3>() = (turn.angle() / frame_period_ * turn.axis()).cast<float>();
  rate.tail<3>() = (velocity_.translation() / frame_period_).cast<float>();
  return rate;
}

void DenseTracker::measureReadout() {
  const double information = last_result_.readout_information;
  if (!options_.estimate_readout || !velocity_measured_ || !(information > 0) ||
      !std::isfinite(last_result_.readout_step))
    return;
  const double measured = readout_ + last_result_.readout_step;
  readout_weight_ += information;
  readout_mean_ += (measured - readout_mean_) * information / readout_weight_;
  readout_ = std::clamp(readout_mean_, 0.0, frame_period_);
}

std::string DenseTracker::report() const {
  if (!options_.estimate_readout) return {};
  // The configured value's share of the estimate: the rest is what alignments measured.
  const double configured =
      readout_weight_ > 0 ? options_.readout_prior_weight / readout_weight_ : 1.0;
  char text[200];
  std::snprintf(text, sizeof(text),
                "rolling shutter readout %.1f ms (camera.readout: %.4f; the configured %.4f "
                "weighs %.0f%% of it, what tracking measured the rest)",
                readout_ * 1e3, readout_, options_.readout, 100.0 * configured);
  return text;
}

bool DenseTracker::relocalise(const Frame& frame, Eigen::Isometry3d& pose) {
  // First the cheap way: the camera is often near where it was lost (a blank or bad frame).
  const Eigen::Isometry3d from_last = rigid(last_pose_.inverse() * keyframe_->pose);
  AlignmentResult result = aligner_.align(keyframe_->reference, pyramid_, from_last);
  pose = rigid(keyframe_->pose * result.motion.inverse());
  if (!reject(result, pose, last_pose_, 1.0, true)) return true;

  // Then features, newest keyframe first; the dense aligner refines what PnP finds.
  relocaliser_.prepare(frame);
  for (auto it = keyframes_.rbegin(); it != keyframes_.rend(); ++it) {
    Keyframe& keyframe = **it;
    const std::optional<Eigen::Isometry3d> found = relocaliser_.locate(keyframe.view);
    if (!found) continue;
    result = aligner_.align(keyframe.reference, pyramid_, *found);
    pose = rigid(keyframe.pose * result.motion.inverse());
    // PnP and the dense refinement must agree: two independent methods on one wrong answer
    // are unlikely.
    const Eigen::Isometry3d change = found->inverse() * result.motion;
    if (reject(result, pose, pose, 1.0, false) || change.translation().norm() > 0.05 ||
        angle(change) > 0.09)
      continue;
    keyframe_ = *it;
    return true;
  }
  return false;
}

}  // namespace rgbdmap
