// The PLY meshes `render` and `view` read (readPly, what --mesh writes): a mesh or an InputError
// naming the file, never a crash, a read past the data or an allocation the file cannot back.
#include "fuzz_input.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/map_files/ply_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdmap;
  const std::string path = fuzz::scratchDir() + "/mesh.ply";
  fuzz::writeFile(path, std::string(reinterpret_cast<const char*>(data), size));
  try {
    (void)readPly(path);
  } catch (const InputError&) {
  }
  return 0;
}
