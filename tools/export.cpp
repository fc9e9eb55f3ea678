// `rgbdmap export MAP.store -o MAP.pcd`: the map a run's store holds (the last checkpoint's, or
// the final map) as one PCD, without the run: after a crash, or while the run goes on.
#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/map_files/map_store.hpp"
#include "rgbdmap/map_files/pcd_file.hpp"
#include "rgbdmap/tools/commands.hpp"

namespace rgbdmap {

void addExportCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "export", "write the map a map store (MAP.store, beside MAP.pcd) holds as one PCD");
  auto path = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  cmd->add_option("store", *path, "the store folder a run writes beside its map, MAP.store")
      ->required();
  cmd->add_option("-o,--out", *out, "the PCD to write")->required();
  cmd->callback([path, out, &selected] {
    selected = [path, out] {
      const auto start = std::chrono::steady_clock::now();
      const MapCloud map = readMapStore(*path);
      std::string error;
      if (!writePcdAtomically(map, *out, error)) throw std::runtime_error(error);
      std::printf("%s: %zu points written to %s in %.2f s\n", path->c_str(), map.size(),
                  out->c_str(), secondsSince(start));
      return 0;
    };
  });
}

}  // namespace rgbdmap
