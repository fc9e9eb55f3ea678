#include "rgbdmap/runtime/checkpoint_writer.hpp"

#include <fcntl.h>
#include <pcl/io/pcd_io.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>

namespace rgbdmap {
namespace {

bool fsyncPath(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

std::string folderOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

}  // namespace

bool writePcdAtomically(const MapCloud& cloud, const std::string& path, std::string& error) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  int status = -1;
  try {
    if (cloud.empty()) {
      // PCL refuses to write an empty cloud; an empty map is still a valid answer.
      const std::string header =
          pcl::PCDWriter::generateHeader<pcl::PointXYZRGB>(cloud, 0) + "DATA binary\n";
      FILE* f = std::fopen(tmp.c_str(), "wb");
      status = (f && std::fwrite(header.data(), 1, header.size(), f) == header.size()) ? 0 : -1;
      if (f && std::fclose(f) != 0) status = -1;
    } else {
      status = pcl::io::savePCDFileBinary(tmp, cloud);
    }
  } catch (const std::exception& e) {
    error = path + ": cannot write map: " + std::strerror(errno) + " (" + e.what() + ")";
    std::remove(tmp.c_str());
    return false;
  }
  if (status != 0) {
    error = path + ": cannot write map to " + tmp + " (" + std::strerror(errno) + ")";
    std::remove(tmp.c_str());
    return false;
  }
  if (!fsyncPath(tmp, O_RDONLY)) {
    error = path + ": fsync of " + tmp + " failed (" + std::strerror(errno) + ")";
    std::remove(tmp.c_str());
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    error = path + ": cannot rename " + tmp + " into place (" + std::strerror(errno) + ")";
    std::remove(tmp.c_str());
    return false;
  }
  fsyncPath(folderOf(path), O_RDONLY | O_DIRECTORY);  // makes the rename itself durable
  return true;
}

CheckpointWriter::CheckpointWriter(Callback on_done)
    : on_done_(std::move(on_done)), thread_([this] { run(); }) {}

CheckpointWriter::~CheckpointWriter() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void CheckpointWriter::submit(std::shared_ptr<const MapCloud> cloud, const std::string& path,
                              std::vector<TrajectoryFile> trajectories) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = std::move(cloud);
    pending_path_ = path;
    pending_trajectories_ = std::move(trajectories);
  }
  wake_.notify_all();
}

CheckpointWriter::Result CheckpointWriter::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return !pending_ && !busy_; });
  return last_;
}

void CheckpointWriter::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] { return stop_ || pending_; });
    if (!pending_) break;  // stop requested and nothing left to write
    std::shared_ptr<const MapCloud> cloud = std::move(pending_);
    const std::string path = pending_path_;
    const std::vector<TrajectoryFile> trajectories = std::move(pending_trajectories_);
    pending_trajectories_.clear();
    pending_.reset();
    busy_ = true;
    lock.unlock();

    Result result;
    result.path = path;
    result.points = cloud->size();
    const auto start = std::chrono::steady_clock::now();
    result.ok = writePcdAtomically(*cloud, path, result.error);
    for (const TrajectoryFile& t : trajectories) {
      try {
        t.trajectory->save(t.path);
      } catch (const std::exception& e) {
        result.error += std::string(result.error.empty() ? "" : "; ") + e.what();
        result.ok = false;
      }
    }
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    (result.ok ? written_ : failed_).fetch_add(1);
    if (on_done_) on_done_(result);

    lock.lock();
    busy_ = false;
    last_ = result;
    if (!pending_) idle_.notify_all();
  }
  idle_.notify_all();
}

}  // namespace rgbdmap
