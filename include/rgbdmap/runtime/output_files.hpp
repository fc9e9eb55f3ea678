#pragma once

#include <memory>
#include <string>
#include <vector>

namespace rgbdmap {

class MapPublisher;

// The files a mapping run writes and the temporary files their writers keep while writing, named
// by one rule for the writers, for the front doors and for the second Ctrl-C that removes them.
// (A writer's temporary file: temporaryFileOf, atomic_write.hpp; a trajectory's spool:
// spoolFileOf, trajectory_stream.hpp.)

// Where a run's outputs go.
struct PipelineOutputs {
  std::string map_path = "map.pcd";
  std::string trajectory_path;        // keyframe poses, TUM format ("" = none)
  std::string frame_trajectory_path;  // the pose of every frame, TUM format ("" = none)
  std::string config_path;            // effective configuration ("" = none)
  std::string mesh_path;     // triangle mesh (binary PLY) written with every map save ("" = none)
  std::string grid_path;     // occupancy grid (PGM + YAML) written with every map save ("" = none)
  std::string octomap_path;  // binary OctoMap written with every map save ("" = none)
  std::string session_path;  // MAP.session/ written with every map save ("" = none)
  std::string store_path;    // MAP.store/: every save's changes (map_store.hpp; "" = none)
  bool status_line = true;
  MapPublisher* publisher = nullptr;  // a viewer, fed from the mapping thread (null = none)
};

// The path without its file name's extension: "out/map.pcd" -> "out/map". What follows the file
// name's last dot is the extension, also when that dot is the name's first character
// ("out/.pcd" -> "out/"); a name without a dot is kept whole ("out.d/map" -> "out.d/map").
std::string stem(const std::string& path);

// The files of a run whose map is `map_path`: the map, and beside it MAP_keyframes.txt,
// MAP_trajectory.txt, MAP.yaml, MAP.session and MAP.store (docs/usage.md), with `mesh_path` ("" =
// no mesh).
PipelineOutputs outputsBeside(const std::string& map_path, const std::string& mesh_path = "");
// The files of a run that localises in a saved map (--localise): only the trajectory of every
// frame and the effective configuration, named after `map_path` (which is not written).
PipelineOutputs localisationOutputs(const std::string& map_path);
// MAP.session, the session folder saved beside map MAP.pcd (session_file.hpp).
std::string sessionPathOf(const std::string& map_path);
// MAP.store, the map store beside map MAP.pcd (map_store.hpp).
std::string storePathOf(const std::string& map_path);
// MAP.png, the picture of the map the CLI renders after a run.
std::string picturePathOf(const std::string& map_path);
// Every temporary file the writers of `outputs` may have on disk while the run goes on.
std::vector<std::string> temporaryFiles(const PipelineOutputs& outputs);

// The folder of an output file is created if missing and must be writable: better to refuse at
// once than to find out at the first checkpoint, after mapping for a while. Throws InputError
// naming `option` ("--out", "~out") and the path.
void checkOutputFolder(const std::string& path, const std::string& option);

}  // namespace rgbdmap
