#pragma once

#include <deque>
#include <memory>

#include "rgbdmap/tracking/dense_aligner.hpp"
#include "rgbdmap/tracking/image_pyramid.hpp"
#include "rgbdmap/tracking/keyframe_sink.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"
#include "rgbdmap/tracking/relocaliser.hpp"
#include "rgbdmap/tracking/tracking_options.hpp"

namespace rgbdmap {

// Camera tracking for sources without ground truth: every frame is aligned densely to the last
// keyframe (frame-to-keyframe drifts less than chaining frame-to-frame estimates), starting from
// a constant-velocity prediction. An estimate that fails a plausibility check (too little of the
// keyframe in view, too little depth, a large residual, a jump no hand makes between two frames)
// loses the frame: it keeps the predicted pose and is not mapped. While lost, each frame is
// matched against recent keyframes (dense from the last good pose, then ORB + PnP refined
// densely) until one passes the same checks. The first frame defines the world frame.
// Every frame is anchored to the keyframe it was tracked against (Frame::anchor), and each new
// keyframe goes to the sink, if any (the loop closer), with the motion measured from its
// reference keyframe.
class DenseTracker : public PoseProvider {
 public:
  DenseTracker(const CameraIntrinsics& camera, const TrackingOptions& options, float min_depth,
               float max_depth, KeyframeSink* sink = nullptr);
  ~DenseTracker() override;

  bool estimate(Frame& frame) override;
  std::string describe() const override;
  TrackingState state() const override { return state_; }

  std::string report() const override;

  std::uint64_t keyframes() const { return next_id_ - first_id_; }
  // The rolling shutter's readout tracking works with (s): camera.readout, or what it measured.
  double readout() const { return readout_; }

 private:
  struct Keyframe {
    std::uint64_t id = 0;
    AlignmentReference reference;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    RelocalisationView view;  // features for relocalisation
    // Made with a rolling shutter before the camera's velocity was measured (the first frame):
    // its points are as read, not at mid-readout, so the next tracked frame replaces it.
    bool points_as_read = false;
  };
  // Why an alignment was rejected, or nullptr when it is plausible.
  const char* reject(const AlignmentResult& result, const Eigen::Isometry3d& pose,
                     const Eigen::Isometry3d& predicted, double dt, bool check_jump) const;
  // `from`: the keyframe the frame was tracked against (null for the first), with the alignment.
  void makeKeyframe(const Frame& frame, const Eigen::Isometry3d& pose, const Keyframe* from,
                    const AlignmentResult& alignment);
  bool relocalise(const Frame& frame, Eigen::Isometry3d& pose);
  // No velocity known any more (the start, a loss, a relocalisation): predict no motion.
  void forgetVelocity();
  // The camera's motion per second, at the last velocity (zero before one is measured).
  ReadoutMotion readoutRate() const;
  // The camera's motion over a frame's readout (readout_, s), at the last velocity.
  ReadoutMotion readoutMotion() const { return static_cast<float>(readout_) * readoutRate(); }
  // Folds the last alignment's measurement of the readout into readout_.
  void measureReadout();
  bool accept(Frame& frame, const Eigen::Isometry3d& pose, TrackingState state);
  bool lose(Frame& frame, const Eigen::Isometry3d& predicted);

  CameraIntrinsics camera_;
  TrackingOptions options_;
  float min_depth_, max_depth_;
  DenseAligner aligner_;
  ImagePyramid pyramid_;
  Relocaliser relocaliser_;
  KeyframeSink* sink_;
  std::deque<std::shared_ptr<Keyframe>> keyframes_;  // most recent last
  std::shared_ptr<Keyframe> keyframe_;               // the one tracked against
  AlignmentResult last_result_;
  Eigen::Isometry3d last_pose_ = Eigen::Isometry3d::Identity();  // last good pose
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();   // per frame, last good pair
  bool velocity_measured_ = false;  // velocity_ is from a tracked pair, not a reset
  // The rolling shutter's readout (s): camera.readout, then, with tracking.estimate_readout,
  // the information-weighted mean of what alignments measure, with the weight behind it.
  double readout_;       // in [0, frame period]
  double readout_mean_;  // unclamped, so that noise around 0 averages out
  double readout_weight_;
  double last_timestamp_ = 0.0;
  double frame_period_ = 1.0 / 30.0;
  bool started_ = false;
  bool lost_ = false;
  TrackingState state_ = TrackingState::kNoPose;
  std::uint64_t first_id_;  // the sink's firstKeyframeId()
  std::uint64_t next_id_;
};

}  // namespace rgbdmap
