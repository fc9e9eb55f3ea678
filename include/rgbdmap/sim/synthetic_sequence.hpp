#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/sim/camera_path.hpp"
#include "rgbdmap/sim/synthetic_scene.hpp"

namespace rgbdmap {

// Kinect-v1-like axial depth noise (Khoshelham and Elberink 2012, as used by the ICL-NUIM
// and TUM simulations): sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 metres.
double kinectDepthSigma(double z);

struct SyntheticSequenceOptions {
  int frames = 300;  // 0: one whole tour (path "tour" only)
  double fps = 30.0;
  std::uint64_t seed = 1;        // the camera path's sway and the depth stamps
  std::uint64_t noise_seed = 1;  // the sensor noise: a second pass over a path with fresh noise
  bool noise = true;  // depth noise, dropouts and colour noise; false: exact depth (quantised)
  // The camera's path: "orbit" (HandheldPath), "walk" (WalkPath: round the room along its
  // walls, coming back every lap), "line" (LinePath: once along a wall, never back) or "tour"
  // (TourPath: every room of a building's floor plan, back to the start).
  std::string path = "orbit";
  double tour_speed = 0.5;      // m/s: the tour's top walking speed
  double tour_turn_rate = 0.5;  // rad/s: the tour's top turn rate (sway aside)
  double tour_margin = 0.5;     // m: a tour keeps this far from every surface (the depth's range)
  double loop_seconds = 12.0;   // one circle (orbit) or lap (walk) of the room
  double path_radius = 0.0;     // m: of the circle; 0: scaled to the room (HandheldPath)
  double path_inset = 0.0;      // m from the walls (walk, line); 0: 20% of the room's width
  // Sensor errors that make odometry drift as a real camera's does; 0: an ideal sensor. Depth
  // is measured (1 + depth_scale_error) times too far; the lens' focal lengths are
  // (1 + focal_error) times those declared (`camera`, what the mapper assumes); the colour
  // gain drifts by +-brightness_drift (a slow auto-exposure, period 6 s).
  double depth_scale_error = 0.0;
  double focal_error = 0.0;
  double brightness_drift = 0.0;
  // Depth from a camera of its own, at this pose in the colour camera's frame (translation in
  // m, rotation vector in rad; zero: registered to colour), with the declared intrinsics but
  // for its focal length (depth_focal px; 0: the declared one). The depth images are the depth
  // camera's; the reference surface is what it measures. Its intrinsics are exact: focal_error
  // is then the colour camera's alone (what `rgbdmap calibrate` is to find).
  Eigen::Vector3d depth_camera_position = Eigen::Vector3d::Zero();
  Eigen::Vector3d depth_camera_rotation = Eigen::Vector3d::Zero();
  double depth_focal = 0.0;
  bool depthUnregistered() const {
    return !depth_camera_position.isZero() || !depth_camera_rotation.isZero() || depth_focal > 0;
  }
  // A rolling shutter: rows are read one after another over `readout` seconds, top to bottom,
  // the middle row at the frame's stamp (where the ground truth is); each row is rendered at the
  // camera's pose when it was read, colour and depth alike. 0: a global shutter.
  double readout = 0.0;
  double start_time = 1700000000.0;  // first colour stamp (s), Unix-epoch-like as in TUM
  // Depth stamps follow colour by depth_offset + up to depth_offset_jitter (TUM: 5-20 ms,
  // always inside the 0.02 s association window). Both images are rendered at the colour
  // stamp's pose, so the map error measures the mapper, not a time skew between the images.
  double depth_offset = 0.004;
  double depth_offset_jitter = 0.004;
  double groundtruth_rate = 100.0;  // Hz, as TUM's motion capture
  CameraIntrinsics camera;          // default: 640x480, fx = fy = 525, cx = 319.5, cy = 239.5
  double depth_scale = 5000.0;      // units per metre in the 16-bit PNGs
  double min_range = 0.5;           // m: no depth nearer or farther (0 in the image)
  double max_range = 4.5;
  double dropout = 0.02;            // share of pixels missing at random (with noise)
  double max_incidence_deg = 78.0;  // steeper views of a surface give no depth (with noise)
  double color_noise = 2.0;         // grey levels, Gaussian (with noise)
  double surface_voxel = 0.005;     // m: spacing of visible_surface.pcd
  int png_compression = 1;          // zlib level: fast to write, fast to read
  double camera_margin = 0.25;      // m: the path must stay this far from every surface
};

struct SyntheticSequenceSummary {
  int frames = 0;
  std::size_t surface_points = 0;  // in visible_surface.pcd
  double valid_depth_share = 0.0;  // pixels with a depth measurement
  double seconds = 0.0;            // wall time of the generation
  double path_length = 0.0;        // m walked by a tour (0 for the other paths)
  double path_seconds = 0.0;       // s of one tour (0 for the other paths)
};

// Renders a camera's view of the scene: z-depth in metres (0 = no hit) without noise, the lit
// colour (BGR) and the cosine of the incidence angle, for all pixels. Rays are precomputed for
// the intrinsics (no distortion).
class SyntheticRenderer {
 public:
  SyntheticRenderer(const SyntheticScene& scene, const CameraIntrinsics& camera);
  // depth: CV_32FC1, color: CV_8UC3, incidence_cos: CV_32FC1, hits: CV_32FC3 world points.
  void render(const Eigen::Isometry3d& pose, cv::Mat& depth, cv::Mat& color, cv::Mat& incidence_cos,
              cv::Mat& hits) const;
  // The same with row v seen from row_poses[v] (a rolling shutter): one pose per row.
  void render(const std::vector<Eigen::Isometry3d>& row_poses, cv::Mat& depth, cv::Mat& color,
              cv::Mat& incidence_cos, cv::Mat& hits) const;

 private:
  const SyntheticScene& scene_;
  CameraIntrinsics camera_;
  std::vector<Eigen::Vector3d> rays_;  // per pixel, camera frame, z = 1
  Eigen::Vector3d light_;              // a lamp under the ceiling, for view-independent shading
};

// The camera path `options` ask for through `room` (a sequence of `duration` seconds); not a
// tour, which needs a scene's floor plan.
std::unique_ptr<CameraPath> makeCameraPath(const ScenePrimitive& room,
                                           const SyntheticSequenceOptions& options,
                                           double duration);
// The same in `scene`; a tour follows the scene's floor plan (InputError if it has none).
std::unique_ptr<CameraPath> makeCameraPath(const SyntheticScene& scene,
                                           const SyntheticSequenceOptions& options,
                                           double duration);

// Writes a TUM-layout sequence folder (rgb/, depth/, rgb.txt, depth.txt, groundtruth.txt,
// accelerometer.txt, scene.yaml, visible_surface.pcd) of `scene` seen along the options' camera
// path. Deterministic for a
// seed. Throws InputError if the folder cannot be written or the path would leave free space.
SyntheticSequenceSummary writeSyntheticSequence(const std::string& folder,
                                                const SyntheticScene& scene,
                                                const SyntheticSequenceOptions& options);

}  // namespace rgbdmap
