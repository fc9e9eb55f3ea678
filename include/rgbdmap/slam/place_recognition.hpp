#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/slam/loop_options.hpp"
#include "rgbdmap/tracking/dense_aligner.hpp"
#include "rgbdmap/tracking/image_pyramid.hpp"
#include "rgbdmap/tracking/keyframe_sink.hpp"
#include "rgbdmap/tracking/packed_reference.hpp"
#include "rgbdmap/tracking/relocaliser.hpp"
#include "rgbdmap/tracking/tracking_options.hpp"

namespace rgbdmap {

// A loop found between an earlier keyframe and the newest one, verified geometrically.
struct LoopMeasurement {
  int earlier = 0, later = 0;                                          // keyframe ids
  Eigen::Isometry3d later_in_earlier = Eigen::Isometry3d::Identity();  // X_earlier^-1 * X_later
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();  // per pixel
  int matches = 0, inliers = 0;
  double overlap = 0.0;
};

// The tracker's alignment settings made finer and geometric for verifying loops (LoopOptions:
// finest_level, depth_weight).
TrackingOptions loopVerificationOptions(const TrackingOptions& tracking, const LoopOptions& loop);

// A dense alignment (which maps the earlier keyframe's points into the later camera) as a
// measurement of the later keyframe in the earlier one: later_in_earlier, information and
// overlap (ids and counts left to the caller).
LoopMeasurement measurementOf(const AlignmentResult& dense);

// Loop closure's checks of a dense alignment (`verification`: loopVerificationOptions) started
// from the features' pose `by_features` (both map the earlier keyframe's points into the later
// camera): it overlaps, fits, agrees with the features and joins near views. The measurement
// (later_in_earlier, information, overlap; ids and counts left to the caller), or none.
std::optional<LoopMeasurement> verifiedLoop(const AlignmentResult& dense,
                                            const Eigen::Isometry3d& by_features,
                                            const TrackingOptions& verification,
                                            const LoopOptions& loop);

// Finds where the newest keyframe has been before: keeps each keyframe's appearance (ORB
// features with 3-D points) and its dense alignment reference; among the earlier keyframes a
// caller proposes (near it, by pose), the best-matching few are verified with PnP RANSAC and
// then the dense aligner started from the PnP pose. Both must agree and the dense alignment must
// pass the tracker's own plausibility checks: two independent methods rarely agree on a wrong
// place.
class PlaceRecognition {
 public:
  // What a keyframe is recognised by: its ORB features with their 3-D points, and its dense
  // alignment reference (packed: kept as long as the place). Never changed once added (a saved
  // session shares them).
  struct Place {
    RelocalisationView view;
    PackedReference reference;
  };
  struct Counts {
    int proposed = 0;  // looked alike (enough ORB matches)
    int verified = 0;  // passed the geometric checks
  };

  // `tracking`: the tracker's alignment settings, made finer for loops by `loop`; depth outside
  // [min_depth, max_depth] (filter.*) is not used.
  PlaceRecognition(const CameraIntrinsics& camera, const TrackingOptions& tracking,
                   const LoopOptions& loop, double min_depth, double max_depth);

  // Takes in the newest keyframe (its images are let go after this). Call before find().
  void add(const TrackedKeyframe& keyframe);
  // Takes in a place saved by an earlier run (a session's) as keyframe `id`'s.
  void restore(int id, std::shared_ptr<const Place> place);
  // The best verified loop from the newest keyframe to one of `candidates` (ids, nearest
  // first), or none.
  std::optional<LoopMeasurement> find(const std::vector<int>& candidates, Counts& counts);
  bool described(int id) const;
  // Lets a keyframe's appearance go (it stays a node of the graph, but no later keyframe can
  // find it).
  void forget(int id);
  std::size_t memoryBytes() const;
  // The places as they are now, by keyframe id (null where none): shared, not copied. Safe to
  // call from any thread.
  std::vector<std::shared_ptr<const Place>> places() const;

 private:
  CameraIntrinsics camera_;
  TrackingOptions tracking_;
  LoopOptions options_;
  float min_depth_, max_depth_;
  Relocaliser features_;
  DenseAligner aligner_;
  ImagePyramid pyramid_;          // of the newest keyframe
  AlignmentReference reference_;  // scratch: a place's reference, built or expanded
  // By keyframe id; null for a keyframe not described or forgotten. Pointers, so that growing
  // the table never copies the places (tens of MB in a long run).
  // Written on the caller's (loop) thread only, under `entries_mutex_` for places().
  std::vector<std::shared_ptr<const Place>> entries_;
  mutable std::mutex entries_mutex_;
};

}  // namespace rgbdmap
