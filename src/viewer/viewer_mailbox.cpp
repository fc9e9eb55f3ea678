#include "rgbdmap/viewer/viewer_mailbox.hpp"

namespace rgbdmap {

void ViewerMailbox::publishFrame(const Frame& frame, const PublishedStatus& status) {
  // Checked before locking: most frames carry no images for the viewer.
  const bool copy_images = images_taken_.load() && !frame.color.empty() && !frame.depth.empty();
  std::lock_guard<std::mutex> lock(mutex_);
  if (copy_images) {
    frame.color.copyTo(pending_.color);  // same size every frame: reuses the buffer
    frame.depth.copyTo(pending_.depth);
    pending_.has_images = true;
    images_taken_.store(false);
  }
  if (frame.has_pose) {
    pending_.new_points.push_back({frame.pose.translation(), status.keyframe});
    pending_.pose = frame.pose;
    pending_.has_pose = true;
  }
  pending_.status = status;
  pending_.has_status = true;
  changed_ = true;
}

void ViewerMailbox::publishMap(std::shared_ptr<const MapCloud> map) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.map = std::move(map);
  map_taken_.store(false);
  changed_ = true;
}

void ViewerMailbox::publishMesh(std::shared_ptr<const TriangleMesh> mesh) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.mesh = std::move(mesh);
  changed_ = true;
}

void ViewerMailbox::publishTrajectory(const std::vector<TrajectoryPoint>& points,
                                      const Eigen::Isometry3d& last_pose) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.new_points.insert(pending_.new_points.end(), points.begin(), points.end());
  pending_.pose = last_pose;
  pending_.has_pose = !points.empty();
  changed_ = true;
}

bool ViewerMailbox::take(ViewerUpdate& update) {
  update.new_points.clear();
  update.map.reset();
  update.mesh.reset();
  update.has_images = update.has_pose = update.has_status = false;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!changed_) return false;
  // Swapping keeps both sides' buffers allocated: no allocation in steady state.
  std::swap(update, pending_);
  changed_ = false;
  if (update.has_images) images_taken_.store(true);
  if (update.map) map_taken_.store(true);
  return true;
}

}  // namespace rgbdmap
