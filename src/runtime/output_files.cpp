#include "rgbdmap/runtime/output_files.hpp"

#include <unistd.h>

#include <filesystem>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/map_files/atomic_write.hpp"
#include "rgbdmap/map_files/grid_file.hpp"
#include "rgbdmap/map_files/trajectory_stream.hpp"

namespace rgbdmap {

std::string stem(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  const bool in_file_name = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  return in_file_name ? path.substr(0, dot) : path;
}

PipelineOutputs outputsBeside(const std::string& map_path, const std::string& mesh_path) {
  PipelineOutputs outputs;
  outputs.map_path = map_path;
  outputs.trajectory_path = stem(map_path) + "_keyframes.txt";
  outputs.frame_trajectory_path = stem(map_path) + "_trajectory.txt";
  outputs.config_path = stem(map_path) + ".yaml";
  outputs.session_path = sessionPathOf(map_path);
  outputs.store_path = storePathOf(map_path);
  outputs.mesh_path = mesh_path;
  return outputs;
}

PipelineOutputs localisationOutputs(const std::string& map_path) {
  PipelineOutputs outputs = outputsBeside(map_path);
  outputs.map_path.clear();
  outputs.trajectory_path.clear();  // no keyframes are fused
  outputs.session_path.clear();
  outputs.store_path.clear();
  return outputs;
}

std::string sessionPathOf(const std::string& map_path) { return stem(map_path) + ".session"; }

std::string storePathOf(const std::string& map_path) { return stem(map_path) + ".store"; }

std::string picturePathOf(const std::string& map_path) { return stem(map_path) + ".png"; }

// The map, the mesh and the grid are written atomically; a trajectory is written atomically first,
// then appended to in place, or, with loop closure, spooled and rewritten atomically. The
// effective configuration is written once, before mapping, and needs no temporary file.
std::vector<std::string> temporaryFiles(const PipelineOutputs& outputs) {
  std::vector<std::string> files;
  for (const std::string* path : {&outputs.map_path, &outputs.mesh_path, &outputs.octomap_path})
    if (!path->empty()) files.push_back(temporaryFileOf(*path));
  if (!outputs.store_path.empty())
    files.push_back(temporaryFileOf(outputs.store_path + "/index.bin"));
  if (!outputs.grid_path.empty()) {
    files.push_back(temporaryFileOf(outputs.grid_path));
    files.push_back(temporaryFileOf(gridYamlPath(outputs.grid_path)));
  }
  for (const std::string* path : {&outputs.trajectory_path, &outputs.frame_trajectory_path}) {
    if (path->empty()) continue;
    files.push_back(temporaryFileOf(*path));
    files.push_back(spoolFileOf(*path));
  }
  return files;
}

void checkOutputFolder(const std::string& path, const std::string& option) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::path(path).parent_path();
  if (folder.empty()) return;
  std::error_code ec;
  if (!fs::is_directory(folder, ec) && !fs::create_directories(folder, ec))
    throw InputError(option + " " + path + ": cannot create the folder " + folder.string() +
                     (ec ? " (" + ec.message() + ")" : ""));
  if (::access(folder.c_str(), W_OK) != 0)
    throw InputError(option + " " + path + ": the folder " + folder.string() + " is not writable");
}

}  // namespace rgbdmap
