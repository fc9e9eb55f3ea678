#include "rgbdmap/runtime/checkpoint_writer.hpp"

#include <chrono>
#include <vector>

#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/base/thread_name.hpp"
#include "rgbdmap/map_files/grid_file.hpp"
#include "rgbdmap/map_files/octomap_file.hpp"
#include "rgbdmap/map_files/pcd_file.hpp"
#include "rgbdmap/map_files/ply_file.hpp"

namespace rgbdmap {

CheckpointWriter::CheckpointWriter(Callback on_done, const std::string& store_path)
    : on_done_(std::move(on_done)),
      store_(store_path.empty() ? nullptr : std::make_unique<MapStore>(store_path)),
      thread_([this] { run(); }) {}

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
  if (writeSession(*session.session, session.path, error, &result.session_bytes,
                   &session_appends_)) {
    result.session_path = session.path;
    result.session_appended = session_appends_.appended;
  } else {
    addFailure(result, "session " + error);
  }
  result.session_seconds = secondsSince(start);
}

void CheckpointWriter::writeStore(const MapCloud& cloud, Result& result) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  if (store_->write(cloud, result.store, error))
    result.store_path = store_->path();
  else
    addFailure(result, "map store " + error);
  result.store_seconds = secondsSince(start);
}

void CheckpointWriter::run() {
  nameThisThread("rgbdmap-save");
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
    // No path: the map goes to the store alone, or a run that maps nothing (localisation)
    // writes only its trajectories.
    result.ok = path.empty() || writePcdAtomically(*cloud, path, result.error);
    // The destination still holds the last complete map (or nothing): say which.
    if (path.empty()) {
      // Nothing asked of the PCD this time.
    } else if (result.ok) {
      last_good_ = result;
    } else if (last_good_.ok && last_good_.path == path) {
      result.error += "; the last good map (" + std::to_string(last_good_.points) +
                      " points) is still complete at " + path;
    } else {
      result.error += "; no complete map has been written to " + path + " yet";
    }
    if (store_) writeStore(*cloud, result);
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
