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
  out += tumPoseLine(timestamp, pose);
  if (anchor) out += ' ' + std::to_string(*anchor);
  out.push_back('\n');
}

std::string failure(const std::string& file, const char* what) {
  return file + ": " + what + ": " + std::strerror(errno);
}

}  // namespace

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
                              bool with_anchor, bool truncate, std::string& error) {
  std::string text;
  if (truncate && !with_anchor) text = kTumPoseHeader;
  for (const Entry& e : entries)
    formatLine(text, e.timestamp, e.pose, with_anchor ? &e.anchor : nullptr);
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (truncate ? O_TRUNC : O_APPEND);
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
        while (std::getline(in, line)) {
          std::istringstream fields(line);
          double timestamp;
          Eigen::Vector3d t;
          Eigen::Quaterniond q;
          long long anchor;
          if (!(fields >> timestamp >> t.x() >> t.y() >> t.z() >> q.x() >> q.y() >> q.z() >>
                q.w() >> anchor))
            continue;  // a line cut short by a crash before this run's first persist
          Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
          pose.linear() = q.normalized().toRotationMatrix();
          pose.translation() = t;
          formatLine(text, timestamp, snapshot.apply(anchor, pose), nullptr);
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
  const bool truncate = !started_;
  const bool ok =
      append(corrections_ ? spool_ : path_, entries, corrections_ != nullptr, truncate, error);
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
