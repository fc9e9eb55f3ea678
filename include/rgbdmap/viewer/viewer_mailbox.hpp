#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdmap/mapping/triangle_mesh.hpp"
#include "rgbdmap/runtime/map_publisher.hpp"

namespace rgbdmap {

// A camera position on the trajectory, and whether its frame was fused into the map.
struct TrajectoryPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool keyframe = false;
};

// What changed since the viewer last looked.
struct ViewerUpdate {
  bool has_images = false;
  cv::Mat color;                            // CV_8UC3 BGR, the newest frame
  cv::Mat depth;                            // CV_32FC1 metres
  std::vector<TrajectoryPoint> new_points;  // every posed frame since the last take, in order
  bool has_pose = false;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // newest camera pose
  bool has_status = false;
  PublishedStatus status;
  std::shared_ptr<const MapCloud> map;       // newest map, null when unchanged
  std::shared_ptr<const TriangleMesh> mesh;  // a saved mesh to show (`view MESH.ply`), or null
};

// Hands the mapping thread's frames and maps to the viewer thread. The mapping thread only
// appends a position and copies images when the viewer has taken the previous ones (at the
// viewer's refresh rate, not the camera's); the lock is held for copies and swaps, never while
// drawing.
class ViewerMailbox : public MapPublisher {
 public:
  void publishFrame(const Frame& frame, const PublishedStatus& status) override;
  bool wantsMap() const override { return map_taken_.load(); }
  void publishMap(std::shared_ptr<const MapCloud> map) override;

  // A saved mesh, drawn as shaded triangles instead of the map's points.
  void publishMesh(std::shared_ptr<const TriangleMesh> mesh);

  // For a saved map: the whole trajectory at once.
  void publishTrajectory(const std::vector<TrajectoryPoint>& points,
                         const Eigen::Isometry3d& last_pose);

  // Moves everything new into `update` (whose old contents are recycled); false if nothing is.
  bool take(ViewerUpdate& update);

 private:
  mutable std::mutex mutex_;
  ViewerUpdate pending_;
  bool changed_ = false;
  std::atomic<bool> images_taken_{true};
  std::atomic<bool> map_taken_{true};
};

}  // namespace rgbdmap
