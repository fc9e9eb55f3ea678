#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "rgbdmap/map_files/map_store.hpp"
#include "rgbdmap/map_files/trajectory_stream.hpp"
#include "rgbdmap/mapping/free_space_map.hpp"
#include "rgbdmap/mapping/ground_frame.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/occupancy_grid.hpp"
#include "rgbdmap/mapping/triangle_mesh.hpp"
#include "rgbdmap/sessions/session_file.hpp"

namespace rgbdmap {

// A background thread that writes map snapshots while mapping goes on. Only the newest pending
// snapshot is kept: if mapping produces snapshots faster than the disk takes them, older
// unwritten ones are superseded (each is a complete map).
class CheckpointWriter {
 public:
  struct Result {
    bool ok = false;
    std::string path;
    std::string error;
    std::size_t points = 0;
    double seconds = 0.0;
    std::size_t mesh_triangles = 0;  // in the mesh written with the map (none: 0)
    double mesh_seconds = 0.0;       // writing it (part of `seconds`)
    // The occupancy grid written with the map (none: null), how long finding the floor, building
    // and writing it took (part of `seconds`), and where up and the floor came from.
    std::shared_ptr<const OccupancyGrid> grid;
    double grid_seconds = 0.0;
    std::string ground;          // GroundFrame::describe()
    std::string ground_sources;  // GroundFrame::sources()
    // The OctoMap written with the map (none: empty path): its leaves and how long it took.
    std::string octomap_path;
    std::size_t octomap_occupied = 0, octomap_free = 0;
    double octomap_seconds = 0.0;
    // The session written with the map (none: empty path): its size and how long it took.
    std::string session_path;
    std::uint64_t session_bytes = 0;
    // Images and places new since the last session (the rest linked, not written).
    std::uint64_t session_appended = 0;
    double session_seconds = 0.0;
    // The map store written (none: empty path): what changed, and how long it took.
    std::string store_path;
    MapStore::Written store;
    double store_seconds = 0.0;
  };
  using Callback = std::function<void(const Result&)>;
  // A trajectory written beside the map in the same checkpoint: what it recorded since the last.
  using TrajectoryFile = std::shared_ptr<TrajectoryStream>;
  // A mesh written beside the map in the same checkpoint (binary PLY, atomically like the map).
  struct MeshFile {
    std::shared_ptr<const TriangleMesh> mesh;  // null: no mesh
    std::string path;
  };
  // An occupancy grid drawn from the map and written beside it (PGM and YAML, see grid_file.hpp),
  // on the writer's thread: finding the floor and drawing the grid never holds up mapping.
  struct GridFile {
    std::string path;  // "": no grid
    UpEvidence evidence;
    UpOptions up;
    GridOptions grid;
  };
  // An OctoMap of the map and the free space seen (a copy taken on the fusion thread), written
  // beside it (octomap_file.hpp).
  struct OctomapFile {
    std::shared_ptr<const FreeSpaceMap> free_space;  // null: no OctoMap
    std::string path;
  };

  // The session saved beside the map (session_file.hpp): the places and graph, the kept
  // keyframes' images (shared with the mapper, not copied), the camera and configuration.
  struct SessionFile {
    std::shared_ptr<const Session> session;  // null: no session
    std::string path;
  };

  // `store_path`: the map store (map_store.hpp) every snapshot goes to, what changed since the
  // last ("" = none).
  explicit CheckpointWriter(Callback on_done = nullptr, const std::string& store_path = "");
  ~CheckpointWriter();  // finishes a pending write, then stops

  bool hasStore() const { return store_ != nullptr; }
  // The snapshot goes to the PCD at `path` ("" = none this time) and to the store.
  void submit(std::shared_ptr<const MapCloud> cloud, const std::string& path,
              std::vector<TrajectoryFile> trajectories = {}, MeshFile mesh = {}, GridFile grid = {},
              OctomapFile octomap = {}, SessionFile session = {});
  // Waits until nothing is pending or being written. Returns the last result.
  Result flush();
  std::uint64_t written() const { return written_.load(); }
  std::uint64_t failed() const { return failed_.load(); }

 private:
  void run();
  void writeMesh(const MeshFile& mesh, Result& result);
  void writeGrid(const MapCloud& cloud, const GridFile& grid, Result& result);
  void writeOctomap(const MapCloud& cloud, const OctomapFile& octomap, Result& result);
  void writeSessionFile(const SessionFile& session, Result& result);
  void writeStore(const MapCloud& cloud, Result& result);

  Callback on_done_;
  std::unique_ptr<MapStore> store_;  // used by the writer's thread only
  SessionAppends session_appends_;   // the same
  std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::shared_ptr<const MapCloud> pending_;
  std::string pending_path_;
  std::vector<TrajectoryFile> pending_trajectories_;
  MeshFile pending_mesh_;
  GridFile pending_grid_;
  OctomapFile pending_octomap_;
  SessionFile pending_session_;
  bool busy_ = false;
  bool stop_ = false;
  Result last_;
  Result last_good_;  // the writer thread's own: the last write that succeeded
  std::atomic<std::uint64_t> written_{0}, failed_{0};
  std::thread thread_;
};

}  // namespace rgbdmap
