// rgb.txt, depth.txt and groundtruth.txt of a TUM folder (parts split at 0x01 bytes): any bytes
// give a TumSequence or an InputError naming the file, never a crash or another exception.
#include "fuzz_input.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdmap;
  const std::string dir = fuzz::scratchDir() + "/seq";
  std::filesystem::create_directories(dir);
  const std::vector<std::string> parts = fuzz::split(data, size, 3);
  const char* names[] = {"rgb.txt", "depth.txt", "groundtruth.txt"};
  for (std::size_t i = 0; i < 3; ++i) {
    if (i < parts.size())
      fuzz::writeFile(dir + "/" + names[i], parts[i]);
    else
      std::filesystem::remove(dir + "/" + names[i]);
  }
  try {
    const TumSequence sequence(dir);
    (void)sequence.framesWithoutPose();
  } catch (const InputError&) {
  }
  return 0;
}
