#include "rgbdmap/map_files/trajectory_stream.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "rgbdmap/base/file_io.hpp"
#include "rgbdmap/base/tum_pose_line.hpp"
#include "rgbdmap/map_files/atomic_write.hpp"

namespace rgbdmap {
namespace {

// One TUM line, with the anchor appended for the spool.
void formatLine(std::string& out, double timestamp, const Eigen::Isometry3d& pose,
                const std::int64_t* anchor) {
  out += anchor ? spoolLine({timestamp, pose, *anchor}) : tumPoseLine(timestamp, pose);
  out.push_back('\n');
}

std::string failure(const std::string& file, const char* what) {
  return file + ": " + what + ": " + std::strerror(errno);
}

}  // namespace

std::string spoolLine(const AnchoredPose& pose) {
  return tumPoseLine(pose.timestamp, pose.pose) + ' ' + std::to_string(pose.anchor);
}

bool parseSpoolLine(const std::string& line, AnchoredPose& pose) {
  std::istringstream fields(line);
  Eigen::Vector3d t;
  Eigen::Quaterniond q;
  long long anchor;
  if (!(fields >> pose.timestamp >> t.x() >> t.y() >> t.z() >> q.x() >> q.y() >> q.z() >> q.w() >>
        anchor) ||
      !t.allFinite() || !q.coeffs().allFinite() || q.norm() < 1e-6)
    return false;
  std::string rest;
  if (fields >> rest) return false;
  pose.pose = Eigen::Isometry3d::Identity();
  pose.pose.linear() = q.normalized().toRotationMatrix();
  pose.pose.translation() = t;
  pose.anchor = anchor;
  return true;
}

std::string spoolFileOf(const std::string& trajectory_path) {
  return trajectory_path + ".anchored";
}

TrajectoryStream::TrajectoryStream(std::string path, const PoseCorrections* corrections)
    : path_(std::move(path)), spool_(spoolFileOf(path_)), corrections_(corrections) {}

TrajectoryStream::~TrajectoryStream() {
  if (corrections_ && started_) std::remove(spool_.c_str());
}

void TrajectoryStream::record(double timestamp, const Eigen::Isometry3d& pose,
                              std::int64_t anchor) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.push_back({timestamp, pose, anchor});
}

bool TrajectoryStream::append(const std::string& file, const std::vector<Entry>& entries,
                              bool with_anchor, bool replace, std::string& error) {
  std::string text;
  if (replace && !with_anchor) text = kTumPoseHeader;
  for (const Entry& e : entries)
    formatLine(text, e.timestamp, e.pose, with_anchor ? &e.anchor : nullptr);
  // The first write replaces what an earlier run left. The trajectory itself is renamed into
  // place whole, so that a reader never finds it emptied (truncated in place, it would be until
  // the write ends); the spool, which only this run reads, is truncated. Later writes only add
  // lines.
  if (replace && !with_anchor) return writeBytesAtomically(file, text, error);
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (replace ? O_TRUNC : O_APPEND);
  const int fd = ::open(file.c_str(), flags, 0644);
  if (fd < 0) {
    error = failure(file, "cannot open");
    return false;
  }
  const bool ok = writeAll(fd, text.data(), text.size()) && ::fdatasync(fd) == 0;
  if (!ok) error = failure(file, "cannot write");
  ::close(fd);
  return ok;
}

bool TrajectoryStream::rewriteFromSpool(std::string& error) {
  const PoseCorrections::Snapshot snapshot = corrections_->snapshot();
  std::ifstream in(spool_);
  if (!in) {
    error = failure(spool_, "cannot read");
    return false;
  }
  return writeFileAtomically(
      path_,
      [&](int fd) {
        // In pieces: the spool of a long run is large and only the file should hold it whole.
        std::string text = kTumPoseHeader;
        std::string line;
        AnchoredPose p;
        while (std::getline(in, line)) {
          if (!parseSpoolLine(line, p)) continue;  // cut short by a crash before a first persist
          // Continuing, until the run joins the saved map: the saved runs' poses (anchored below
          // the run's first keyframe) are in another frame than the run's own; its own only.
          if (!snapshot.joined && p.anchor >= 0 && p.anchor < snapshot.first_own) continue;
          formatLine(text, p.timestamp, snapshot.apply(p.anchor, p.pose), nullptr);
          if (text.size() > (1u << 16)) {
            if (!writeAll(fd, text.data(), text.size())) return false;
            text.clear();
          }
        }
        return writeAll(fd, text.data(), text.size());
      },
      error);
}

bool TrajectoryStream::persist(std::string& error) {
  std::vector<Entry> entries;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    entries.swap(pending_);
  }
  const bool replace = !started_;
  const bool ok =
      append(corrections_ ? spool_ : path_, entries, corrections_ != nullptr, replace, error);
  if (!ok) {
    // Keep them for the next try, in order.
    std::lock_guard<std::mutex> lock(mutex_);
    entries.insert(entries.end(), pending_.begin(), pending_.end());
    pending_.swap(entries);
    return false;
  }
  started_ = true;
  return !corrections_ || rewriteFromSpool(error);
}

}  // namespace rgbdmap
