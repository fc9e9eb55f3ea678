#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace rgbdmap {

// How far the pose graph has moved each tracking keyframe from where odometry put it: for
// keyframe k, C_k = X_k * O_k^-1 (X optimised, O odometry), a rigid motion of the odometry
// world. A frame tracked against keyframe k is corrected by C_k (the drift it shares with its
// keyframe), so every pose and every part of the map anchored to a keyframe follows the graph
// without anyone but the graph knowing about loops. Written by the loop thread, read by
// tracking (trajectories), fusion (the map) and the viewer: readers take a snapshot, which is
// a shared immutable table, so reading never waits for an optimisation.
class PoseCorrections {
 public:
  using Table = std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>>;

  struct Snapshot {
    std::shared_ptr<const Table> table;  // by keyframe id
    std::uint64_t version = 0;           // changes whenever a correction does
    // A run that continues a saved session (--continue) takes its keyframe ids from
    // `first_own` on (the saved ones come first). Until it recognises the saved map (`joined`),
    // its own keyframes' corrections are in its own frame and the saved ones' in the saved map's:
    // two maps that nothing ties together yet.
    std::int64_t first_own = 0;
    bool joined = true;
    // The correction of keyframe `anchor`; a keyframe the graph has not taken in yet shares the
    // newest known correction (it was tracked from there), or none when the graph has none of
    // the run's own yet; -1 (no anchor) is not corrected.
    const Eigen::Isometry3d& of(std::int64_t anchor) const;
    Eigen::Isometry3d apply(std::int64_t anchor, const Eigen::Isometry3d& pose) const {
      return of(anchor) * pose;
    }
  };

  PoseCorrections();
  // Loop thread: the corrections of keyframes 0..n-1 (n never shrinks); see Snapshot.
  void publish(Table table, std::int64_t first_own = 0, bool joined = true);
  Snapshot snapshot() const;
  std::uint64_t version() const;

 private:
  mutable std::mutex mutex_;
  Snapshot current_;
};

}  // namespace rgbdmap
