#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <string>

#include "rgbdmap/sim/synthetic_scene.hpp"

namespace rgbdmap {

// Accuracy and completeness of a map against exact geometry, as Tanks and Temples defines them:
// precision = share of map points within tau of the true surface, recall = share of reference
// surface samples with a map point within tau, F = their harmonic mean.
struct MapScore {
  double tau = 0.01;                 // m
  std::size_t map_points = 0;        // finite points scored
  std::size_t reference_points = 0;  // visible surface samples
  double precision = 0.0;
  double recall = 0.0;
  double f_score = 0.0;
  // Distance of map points to the nearest exact surface (m).
  double mean_distance = 0.0;
  double median_distance = 0.0;
  double p95_distance = 0.0;

  std::string toJson() const;
};

// Scores `map` against `scene` (precision, distances) and `reference`, samples of the surface
// the camera saw (recall). Non-finite map points are ignored.
MapScore evaluateMap(const pcl::PointCloud<pcl::PointXYZRGB>& map, const SyntheticScene& scene,
                     const pcl::PointCloud<pcl::PointXYZ>& reference, double tau = 0.01);

// A map file (.pcd or .ply) as coloured points; throws InputError naming the file.
pcl::PointCloud<pcl::PointXYZRGB> loadMapFile(const std::string& path);

// The scene and visible surface of a sequence folder written by `rgbdmap synth`
// (scene.yaml and visible_surface.pcd); throws InputError naming the missing or bad file.
struct SyntheticGroundTruth {
  SyntheticScene scene;
  pcl::PointCloud<pcl::PointXYZ> visible_surface;
};
SyntheticGroundTruth loadSyntheticGroundTruth(const std::string& folder);

}  // namespace rgbdmap
