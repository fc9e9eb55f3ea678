#pragma once

#include <Eigen/Geometry>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/slam/loop_closer.hpp"
#include "rgbdmap/slam/place_recognition.hpp"
#include "rgbdmap/tracking/keyframe_sink.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {

// Poses a run's keyframes in a saved map (a session's graph and places) and adds nothing to it:
// a robot in a known building. On its own thread, each tracking keyframe is looked for among the
// saved places with loop closure's verification (ORB, PnP, dense alignment). A placement says
// where the run's odometry frame lies in the saved map's, T = X * O^-1 (X the pose the place
// gives, O odometry); T is published as the correction of every keyframe since, so the
// trajectories and the poses shown are in the saved map's frame and odometry carries them between
// placements. A first placement is taken only when the next one agrees with it (a place alike in
// appearance elsewhere rarely repeats); later ones must agree with the current T within the drift
// since the last, or with each other (back after a long drift). Memory stays flat: the saved
// places are the only ones, and the newest keyframe goes once it is looked for.
class Localiser : public KeyframeSink {
 public:
  // `saved`: the session's graph and places (poses X of its keyframes). The rest as the loop
  // closer's: `loop` gives the search radius, view angle, drift allowance and agreement limits.
  // lossless: addKeyframe() waits while a keyframe is queued (a replay is placed the same way
  // every time); else a live camera's newest keyframe replaces one still waiting.
  Localiser(const LoopCloser::Saved& saved, const CameraIntrinsics& camera,
            const TrackingOptions& tracking, const LoopOptions& loop, double min_depth,
            double max_depth, PoseCorrections& corrections, RunStats& stats, bool lossless);
  ~Localiser() override;

  void addKeyframe(TrackedKeyframe keyframe) override;
  // Looks for every queued keyframe, then stops the thread.
  void finish();
  // The saved keyframes with a place (what can be recognised).
  std::size_t places() const { return place_ids_.size(); }
  // Keyframes skipped behind a live camera, and the first one placed (-1: none). How many were
  // looked for and placed is in RunStats (keyframes_looked_for, keyframes_placed).
  struct Counts {
    std::uint64_t skipped = 0;
    std::int64_t first_placed = -1;
  };
  Counts counts() const;

 private:
  struct Placement {
    std::uint64_t keyframe = 0;
    double timestamp = 0.0;
    Eigen::Isometry3d odometry_in_map = Eigen::Isometry3d::Identity();  // T
    double walked = 0.0;  // odometry path length at the keyframe
  };

  void run();
  void process(TrackedKeyframe& keyframe);
  // Saved keyframes to compare with, nearest first: near the pose T predicts, or all of them
  // while the run is not placed (or has not been for a long way).
  std::vector<int> candidatesFor(const Eigen::Isometry3d& odometry, double walked) const;
  bool agree(const Placement& a, const Placement& b) const;
  void accept(const Placement& placement);

  LoopOptions options_;
  PoseCorrections& corrections_;
  RunStats& stats_;
  bool lossless_;
  std::vector<Eigen::Isometry3d> saved_poses_;  // X of the saved keyframes, by id
  std::vector<int> place_ids_;                  // saved keyframes with a place
  PlaceRecognition recognition_;                // the saved places, then the newest keyframe

  // Loop thread only.
  std::optional<Placement> current_;    // the placement in use
  std::optional<Placement> candidate_;  // one waiting for a second to agree
  double walked_ = 0.0;
  std::optional<Eigen::Isometry3d> last_odometry_;
  PoseCorrections::Table table_;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<TrackedKeyframe> queue_;
  bool finishing_ = false;
  Counts counts_;
  std::thread thread_;
};

}  // namespace rgbdmap
