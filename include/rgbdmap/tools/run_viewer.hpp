#pragma once

#include <memory>
#include <string>

#include "rgbdmap/runtime/pipeline.hpp"
#include "rgbdmap/viewer/viewer.hpp"

namespace rgbdmap {

// The live viewer of a mapping run, for `--viewer auto|none`: null for none, and for auto when
// no display is available (said once, and the run maps as with none). Its keys act on `control`:
// s as SIGUSR1, q or closing the window as Ctrl-C.
std::unique_ptr<Viewer> openRunViewer(const std::string& mode, RunControl& control,
                                      const std::string& map_path);

}  // namespace rgbdmap
