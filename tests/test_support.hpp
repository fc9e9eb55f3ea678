#pragma once

#include <string>
#include <vector>

#include "rgbdmap/checkpoint_writer.hpp"

namespace rgbdmap::test {

// ../shared/data (the real TUM frames and the .oni recording).
std::string dataDir();
std::string tumDir(const std::string& name);  // dataDir()/tum/<name>
// The rgbdmap executable under test.
std::string binary();
// A fresh empty folder for one test: <build>/tests/tmp/<suite>.<test>.
std::string freshDir();

// Runs a command with /bin/sh; returns the exit code (or 128+signal), stdout+stderr in output.
int run(const std::string& command, std::string* output = nullptr);

// Loads a PCD map; fails the current test if it cannot.
MapCloud loadMap(const std::string& path);

}  // namespace rgbdmap::test
