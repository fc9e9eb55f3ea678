// The configuration: the first line is a `--set key=value`, the rest a YAML file for --config.
// Any bytes give a configuration or an InputError naming the key or file, never a crash.
#include "fuzz_input.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/config/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdmap;
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::size_t newline = input.find('\n');
  const std::string set = input.substr(0, newline);
  const std::string yaml = newline == std::string::npos ? "" : input.substr(newline + 1);
  const std::string path = fuzz::scratchDir() + "/config.yaml";
  fuzz::writeFile(path, yaml);
  Config config;
  try {
    config.loadYaml(path);
  } catch (const InputError&) {
  }
  try {
    const std::size_t eq = set.find('=');
    if (eq != std::string::npos) config.set(set.substr(0, eq), set.substr(eq + 1), "--set");
  } catch (const InputError&) {
  }
  (void)config.toYaml();
  return 0;
}
