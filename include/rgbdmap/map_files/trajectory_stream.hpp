#pragma once

#include <mutex>
#include <string>
#include <vector>

#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"
#include "rgbdmap/tracking/pose_sink.hpp"

namespace rgbdmap {

// A pose as tracked with the keyframe it is anchored to (-1: none), so that the pose graph's
// corrections move it: a line of a spool (below).
struct AnchoredPose {
  double timestamp = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  std::int64_t anchor = -1;
};
// A spool's line: "timestamp tx ty tz qx qy qz qw anchor", without the newline.
std::string spoolLine(const AnchoredPose& pose);
// Reads one back; false for a line that is not one.
bool parseSpoolLine(const std::string& line, AnchoredPose& pose);

// "<path>.anchored": the spool beside a trajectory file when loop closure can still move its
// poses (a second Ctrl-C removes it, see output_files.hpp).
std::string spoolFileOf(const std::string& trajectory_path);

// A trajectory file (TUM format) kept on disk rather than in memory, so that a run of hours holds
// only the poses recorded since the last checkpoint. Poses are recorded from one thread (tracking
// or fusion) and written by another (the checkpoint writer) with persist():
// - without loop closure (`corrections` null) the new lines are appended to the file itself and
//   made durable (fdatasync); the first persist() writes it whole (temp file, fsync, rename);
// - with it, poses move whenever a loop closes, so the poses as tracked are appended with their
//   anchors to a spool file beside it ("<path>.anchored"), and the file is rewritten from the
//   spool with the latest corrections (temp file, fsync, rename). The spool is removed when the
//   stream is destroyed.
class TrajectoryStream : public PoseSink {
 public:
  TrajectoryStream(std::string path, const PoseCorrections* corrections);
  ~TrajectoryStream() override;
  TrajectoryStream(const TrajectoryStream&) = delete;
  TrajectoryStream& operator=(const TrajectoryStream&) = delete;

  void record(double timestamp, const Eigen::Isometry3d& pose, std::int64_t anchor) override;
  // Writes what was recorded since the last call. False with `error` naming the file and the
  // system error when a write fails; the poses not written are kept for the next call.
  bool persist(std::string& error);

  const std::string& path() const { return path_; }
  // The spool, with loop closure ("" without: the file itself holds the poses).
  std::string spool() const { return corrections_ ? spool_ : std::string(); }
  // Reads the file as persist() last left it.
  Trajectory load() const { return Trajectory::load(path_); }

 private:
  using Entry = AnchoredPose;
  bool append(const std::string& file, const std::vector<Entry>& entries, bool with_anchor,
              bool replace, std::string& error);
  bool rewriteFromSpool(std::string& error);

  std::string path_;
  std::string spool_;
  const PoseCorrections* corrections_;
  mutable std::mutex mutex_;
  std::vector<Entry> pending_;  // recorded, not yet written
  bool started_ = false;        // the first persist() replaces what an earlier run left
};

}  // namespace rgbdmap
