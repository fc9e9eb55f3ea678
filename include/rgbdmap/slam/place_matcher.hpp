#pragma once

#include <optional>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/slam/loop_options.hpp"
#include "rgbdmap/slam/place_recognition.hpp"

namespace rgbdmap {

// Whether two places show the same spot, from what places keep alone (no images: places sent
// between robots carry none). ORB matches and PnP RANSAC give a first pose (the query's 3-D points
// projected into its camera stand for its image); then the two dense references, as point sets,
// are aligned by ICP from it. The two must agree, and the aligned references must overlap and
// lie close: loop closure's checks (loop.*), with a geometric alignment for the photometric one.
class PlaceMatcher {
 public:
  struct Options {
    double max_pair = 0.05;         // m: ICP pairs start within this, shrink to `inlier`
    double inlier = 0.01;           // m: a query point this close to the candidate's surface
    double min_overlap = 0.3;       // fraction of the query's points that are inliers at the end
    double max_rms = 0.008;         // m: RMS distance of the inliers
    std::size_t max_points = 6000;  // query points used (evenly spread)
  };

  PlaceMatcher(const CameraIntrinsics& camera, const LoopOptions& loop, Options options);
  PlaceMatcher(const CameraIntrinsics& camera, const LoopOptions& loop)
      : PlaceMatcher(camera, loop, Options{}) {}

  // How many distinctive ORB matches the two share (the ranking before match()).
  int similarity(const PlaceRecognition::Place& a, const PlaceRecognition::Place& b) const;
  // `query` seen from `candidate` (later_in_earlier = X_candidate^-1 * X_query, with the
  // information of the alignment per point), or none; ids are left to the caller.
  std::optional<LoopMeasurement> match(const PlaceRecognition::Place& candidate,
                                       const PlaceRecognition::Place& query) const;

 private:
  CameraIntrinsics camera_;
  LoopOptions loop_;
  Options options_;
};

}  // namespace rgbdmap
