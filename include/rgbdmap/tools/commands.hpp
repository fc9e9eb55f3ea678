#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace rgbdmap {

// A subcommand of the `rgbdmap` program. Each add*Command registers its options on `app`; when
// the subcommand is on the command line, parsing stores the action to run in `selected`.
using Command = std::function<int()>;

void addRenderCommand(CLI::App& app, Command& selected);     // tools/render.cpp
void addAssociateCommand(CLI::App& app, Command& selected);  // tools/associate.cpp
void addDevicesCommand(CLI::App& app, Command& selected);    // tools/devices.cpp
void addRecordCommand(CLI::App& app, Command& selected);     // tools/record.cpp
void addSynthCommand(CLI::App& app, Command& selected);      // tools/synth.cpp
void addEvaluateCommand(CLI::App& app, Command& selected);   // tools/evaluate.cpp
void addViewCommand(CLI::App& app, Command& selected);       // tools/view.cpp
void addSessionCommand(CLI::App& app, Command& selected);    // tools/session.cpp
void addMergeCommand(CLI::App& app, Command& selected);      // tools/merge.cpp
void addExportCommand(CLI::App& app, Command& selected);     // tools/export.cpp
void addCalibrateCommand(CLI::App& app, Command& selected);  // tools/calibrate.cpp

}  // namespace rgbdmap
