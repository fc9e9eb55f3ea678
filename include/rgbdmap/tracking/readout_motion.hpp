#pragma once

#include <Eigen/Core>

namespace rgbdmap {

// A rolling shutter reads an image's rows one after another, top to bottom: the camera's motion
// from the first row's read to the last's (rotation vector, then translation, in the camera's
// frame at mid-readout); zero for a global shutter. Row y was read (y / height - 1/2) of it after
// the middle row, and a pose is the camera's at the middle row.
using ReadoutMotion = Eigen::Matrix<float, 6, 1>;

}  // namespace rgbdmap
