// The PCD/PLY map files `render` and `evaluate` read: the first byte picks the format (even: PCD,
// odd: PLY), the rest is the file. A cloud or an InputError naming the file, never a crash.
#include "fuzz_input.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/eval/map_evaluation.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdmap;
  if (size == 0) return 0;
  const std::string path = fuzz::scratchDir() + (data[0] % 2 == 0 ? "/map.pcd" : "/map.ply");
  fuzz::writeFile(path, std::string(reinterpret_cast<const char*>(data) + 1, size - 1));
  try {
    (void)loadMapFile(path);
  } catch (const InputError&) {
  }
  return 0;
}
