// `rgbdmap render MAP`: a picture of a map file, without a display.
#include <cstdio>
#include <memory>

#include "rgbdmap/tools/commands.hpp"
#include "rgbdmap/tools/map_renderer.hpp"

namespace rgbdmap {

void addRenderCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand("render",
                                 "render a map (PCD/PLY) or mesh (PLY) to a PNG picture, headless");
  struct Options {
    std::string map, trajectory, out;
    MapRenderer renderer;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("map", o->map, "map file (.pcd or .ply) or mesh (.ply, --mesh)")->required();
  cmd->add_option("-o,--out", o->out, "PNG to write (default: the map's name with .png)");
  cmd->add_option("-t,--trajectory", o->trajectory, "TUM trajectory to draw and to place the view");
  cmd->add_option("--width", o->renderer.width, "image width")->check(CLI::Range(64, 8192));
  cmd->add_option("--height", o->renderer.height, "image height")->check(CLI::Range(64, 8192));
  cmd->add_option("--point-radius", o->renderer.point_radius, "splat radius (px)")
      ->check(CLI::Range(0, 10));
  cmd->callback([o, &selected] {
    selected = [o] {
      const std::string out =
          o->out.empty() ? o->map.substr(0, o->map.find_last_of('.')) + ".png" : o->out;
      std::string error;
      if (!renderMapFile(o->map, o->trajectory, out, o->renderer, error)) {
        std::fprintf(stderr, "rgbdmap render: %s\n", error.c_str());
        return 1;
      }
      std::printf("%s\n", out.c_str());
      return 0;
    };
  });
}

}  // namespace rgbdmap
