// A TUM trajectory file (groundtruth.txt, pose.trajectory, `evaluate trajectory` inputs): a
// Trajectory or an InputError, never a crash; interpolation between any two loaded samples is
// finite.
#include <cmath>
#include <cstdlib>

#include "fuzz_input.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/trajectory.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdmap;
  const std::string path = fuzz::scratchDir() + "/trajectory.txt";
  fuzz::writeFile(path, std::string(reinterpret_cast<const char*>(data), size));
  try {
    const Trajectory t = Trajectory::load(path);
    if (!t.empty()) {
      for (const double stamp :
           {t[0].timestamp, 0.5 * (t[0].timestamp + t[t.size() - 1].timestamp)}) {
        const auto pose = t.interpolate(stamp, 1e9);
        if (pose && !pose->matrix().allFinite()) std::abort();
      }
    }
  } catch (const InputError&) {
  }
  return 0;
}
