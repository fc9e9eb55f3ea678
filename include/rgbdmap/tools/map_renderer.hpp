#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/triangle_mesh.hpp"

namespace rgbdmap {

// Renders a coloured point cloud to an image without a display: a virtual pinhole camera looks
// at the map from behind and above the average camera position, points are splatted with a
// z-buffer, and the keyframe trajectory (if given) is drawn as a line.
struct MapRenderer {
  int width = 1280;
  int height = 960;
  int point_radius = 1;  // splat radius in pixels
  double fov_degrees = 60.0;

  cv::Mat render(const MapCloud& cloud, const Trajectory& trajectory) const;
  // A mesh from the same viewpoint: triangles filled with a z-buffer, vertex colours
  // interpolated and shaded by how squarely each face is seen (so that shape shows).
  cv::Mat render(const TriangleMesh& mesh, const Trajectory& trajectory) const;
};

// Loads map (PCD/PLY; a PLY with faces is drawn as a mesh) and, when it exists, a TUM trajectory,
// and writes a PNG.
bool renderMapFile(const std::string& map_path, const std::string& trajectory_path,
                   const std::string& png_path, const MapRenderer& renderer, std::string& error);

}  // namespace rgbdmap
