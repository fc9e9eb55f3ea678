#include "rgbdmap/runtime/checkpoint_writer.hpp"

#include <fcntl.h>
#include <pcl/io/pcd_io.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/runtime/grid_file.hpp"
#include "rgbdmap/runtime/octomap_file.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/runtime/ply_file.hpp"

namespace rgbdmap {
namespace {

std::string folderOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

// "File too large (EFBIG)": the symbolic name for the errors a user can act on.
std::string describeErrno(int error) {
  std::string text = std::strerror(error);
  switch (error) {
    case EFBIG:
      return text + " (EFBIG: a file-size limit, ulimit -f)";
    case ENOSPC:
      return text + " (ENOSPC)";
    case EDQUOT:
      return text + " (EDQUOT)";
    case EROFS:
      return text + " (EROFS)";
    case EACCES:
      return text + " (EACCES)";
    default:
      return text;
  }
}

}  // namespace

namespace {

// Binary PCD with fields x y z rgb (16 bytes a point), written with plain write() calls so that
// every failure comes back as an errno (PCL's writer maps the file, where a full disk is a
// SIGBUS).
bool writePcd(const MapCloud& cloud, int fd) {
  const std::string header =
      pcl::PCDWriter::generateHeader<pcl::PointXYZRGB>(cloud, static_cast<int>(cloud.size())) +
      "DATA binary\n";
  if (!writeAll(fd, header.data(), header.size())) return false;
  constexpr std::size_t kPointBytes = 16;
  constexpr std::size_t kChunk = 16384;
  std::vector<char> buffer(kChunk * kPointBytes);
  for (std::size_t first = 0; first < cloud.size(); first += kChunk) {
    const std::size_t count = std::min(kChunk, cloud.size() - first);
    char* out = buffer.data();
    for (std::size_t i = first; i < first + count; ++i, out += kPointBytes) {
      const pcl::PointXYZRGB& p = cloud.points[i];
      std::memcpy(out, &p.x, 4);
      std::memcpy(out + 4, &p.y, 4);
      std::memcpy(out + 8, &p.z, 4);
      std::memcpy(out + 12, &p.rgba, 4);
    }
    if (!writeAll(fd, buffer.data(), count * kPointBytes)) return false;
  }
  return true;
}

}  // namespace

bool writeFileAtomically(const std::string& path, const std::function<bool(int fd)>& write,
                         std::string& error) {
  const std::string tmp = temporaryFileOf(path);
  const auto fail = [&](const std::string& what, int fd) {
    const int saved = errno;
    error = path + ": " + what + " " + tmp + ": " + describeErrno(saved);
    if (fd >= 0) ::close(fd);
    std::remove(tmp.c_str());
    return false;
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return fail("cannot create", -1);
  if (!write(fd)) return fail("cannot write", fd);
  if (::fsync(fd) != 0) return fail("cannot fsync", fd);  // ENOSPC may only show here (NFS)
  if (::close(fd) != 0) return fail("cannot close", -1);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) return fail("cannot rename into place", -1);
  // Makes the rename itself durable; the map is complete either way.
  const int folder = ::open(folderOf(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (folder >= 0) {
    ::fsync(folder);
    ::close(folder);
  }
  return true;
}

bool writeBytesAtomically(const std::string& path, const std::string& bytes, std::string& error) {
  return writeFileAtomically(
      path, [&bytes](int fd) { return writeAll(fd, bytes.data(), bytes.size()); }, error);
}

bool writePcdAtomically(const MapCloud& cloud, const std::string& path, std::string& error) {
  return writeFileAtomically(
      path, [&](int fd) { return writePcd(cloud, fd); }, error);
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
                              std::vector<TrajectoryFile> trajectories, MeshFile mesh,
                              GridFile grid, OctomapFile octomap, SessionFile session) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = std::move(cloud);
    pending_path_ = path;
    pending_trajectories_ = std::move(trajectories);
    pending_mesh_ = std::move(mesh);
    pending_grid_ = std::move(grid);
    pending_octomap_ = std::move(octomap);
    pending_session_ = std::move(session);
  }
  wake_.notify_all();
}

CheckpointWriter::Result CheckpointWriter::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return !pending_ && !busy_; });
  return last_;
}

namespace {

// A part of the checkpoint that failed: said after what failed before it, and the write not ok.
void addFailure(CheckpointWriter::Result& result, const std::string& message) {
  result.error += (result.error.empty() ? "" : "; ") + message;
  result.ok = false;
}

}  // namespace

void CheckpointWriter::writeMesh(const MeshFile& mesh, Result& result) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  if (writePlyAtomically(*mesh.mesh, mesh.path, error)) {
    result.mesh_triangles = mesh.mesh->triangles.size();
  } else {
    addFailure(result, "mesh " + error);
  }
  result.mesh_seconds = secondsSince(start);
}

void CheckpointWriter::writeGrid(const MapCloud& cloud, const GridFile& grid, Result& result) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  try {
    const GroundFrame ground = GroundFrame::resolve(cloud, grid.evidence, grid.up);
    auto built = std::make_shared<OccupancyGrid>(OccupancyGrid::build(cloud, ground, grid.grid));
    result.ground = ground.describe();
    result.ground_sources = ground.sources();
    if (writeGridAtomically(*built, grid.path, error)) result.grid = std::move(built);
  } catch (const std::exception& e) {
    error = grid.path + ": " + e.what();
  }
  if (!error.empty()) addFailure(result, "grid " + error);
  result.grid_seconds = secondsSince(start);
}

void CheckpointWriter::writeOctomap(const MapCloud& cloud, const OctomapFile& octomap,
                                    Result& result) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  OctomapCounts counts;
  if (writeOctomapAtomically(cloud, *octomap.free_space, octomap.path, counts, error)) {
    result.octomap_path = octomap.path;
    result.octomap_occupied = counts.occupied;
    result.octomap_free = counts.free;
  } else {
    addFailure(result, "OctoMap " + error);
  }
  result.octomap_seconds = secondsSince(start);
}

void CheckpointWriter::writeSessionFile(const SessionFile& session, Result& result) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  if (writeSession(*session.session, session.path, error, &result.session_bytes)) {
    result.session_path = session.path;
  } else {
    addFailure(result, "session " + error);
  }
  result.session_seconds = secondsSince(start);
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
    const MeshFile mesh = std::move(pending_mesh_);
    pending_mesh_ = {};
    const GridFile grid = std::move(pending_grid_);
    pending_grid_ = {};
    const OctomapFile octomap = std::move(pending_octomap_);
    pending_octomap_ = {};
    const SessionFile session = std::move(pending_session_);
    pending_session_ = {};
    pending_.reset();
    busy_ = true;
    lock.unlock();

    Result result;
    result.path = path;
    result.points = cloud->size();
    const auto start = std::chrono::steady_clock::now();
    // No path: a run that maps nothing (localisation) writes only its trajectories.
    result.ok = path.empty() || writePcdAtomically(*cloud, path, result.error);
    // The destination still holds the last complete map (or nothing): say which.
    if (result.ok)
      last_good_ = result;
    else if (last_good_.ok && last_good_.path == path)
      result.error += "; the last good map (" + std::to_string(last_good_.points) +
                      " points) is still complete at " + path;
    else
      result.error += "; no complete map has been written to " + path + " yet";
    if (!grid.path.empty()) writeGrid(*cloud, grid, result);
    if (octomap.free_space) writeOctomap(*cloud, octomap, result);
    // The snapshot (18 MB for a room) goes before the rest is written: the session alone takes
    // longer than the map, and the writer would otherwise hold both for all of it.
    cloud.reset();
    for (const TrajectoryFile& t : trajectories) {
      std::string error;
      if (!t->persist(error)) addFailure(result, error);
    }
    if (mesh.mesh) writeMesh(mesh, result);
    if (session.session) writeSessionFile(session, result);
    result.seconds = secondsSince(start);
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
