#pragma once

#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "rgbdmap/mapping/map_cells.hpp"
#include "rgbdmap/mapping/occupancy_grid.hpp"
#include "rgbdmap/ros/session_publisher.hpp"
#include "rgbdmap/runtime/map_publisher.hpp"

namespace rgbdmap {

// The run as ROS sees it, through the same publisher interface as the viewer: ~map
// (sensor_msgs/PointCloud2, latched, at most every `map_interval` s, thinned to at most
// `map_max_points`), ~map_changes (the cells of the map that changed since the map before, at
// full resolution; a new subscriber first gets every cell of the last map), ~grid
// (nav_msgs/OccupancyGrid drawn from that map, latched, at most every `grid_interval` s; its
// origin is the pose of the grid's corner in map_frame, z up), ~pose (geometry_msgs/PoseStamped)
// and TF map_frame -> camera frame. The pipeline's calls only copy
// into a mailbox; a thread of its own converts and publishes, so ROS never slows mapping.
class RosPublisher : public MapPublisher {
 public:
  struct Options {
    std::string map_frame = "map";
    std::string camera_frame = "camera_rgb_optical_frame";
    double map_interval = 2.0;  // seconds between maps at most
    // ~map's points at most (0: the whole map); ~map_changes always has every point of a cell.
    std::size_t map_max_points = 2'000'000;
    double grid_interval = 5.0;  // seconds between grids at most; negative: no grid
    UpOptions up;
    GridOptions grid;
    // ~session/graph and ~session/places (SessionPublisher); interval <= 0: not streamed.
    SessionPublisher::Options session;
  };
  RosPublisher(ros::NodeHandle& private_nh, Options options);
  ~RosPublisher() override;

  void publishFrame(const Frame& frame, const PublishedStatus& status) override;
  bool wantsMap() const override;
  void publishMap(std::shared_ptr<const MapCloud> map) override;
  void publishUp(const UpEvidence& evidence) override;
  void attachGraph(const LoopCloser* graph, const CameraIntrinsics& camera) override;
  void publishKeyframe(const Frame& keyframe) override;
  // The session stream (null when not streamed).
  SessionPublisher* session() { return session_.get(); }

  // Publishes what is still waiting (the final map) and stops the thread.
  void finish();
  std::uint64_t mapsPublished() const { return maps_published_.load(); }

 private:
  void run();
  void sendPose(double stamp, const Eigen::Isometry3d& pose);
  void sendMap(const MapCloud& map, double stamp);
  void sendChanges(const std::shared_ptr<const MapCloud>& map, double stamp, bool everything);
  void sendGrid(const MapCloud& map, const UpEvidence& up, double stamp);

  Options options_;
  ros::Publisher map_pub_, changes_pub_, pose_pub_, grid_pub_;
  // ~map_changes, the publishing thread's own: the last map (sent whole again, every cell, when
  // someone subscribes) and its cells' hashes.
  std::shared_ptr<const MapCloud> changes_map_;
  double changes_stamp_ = 0.0;
  MapChanges changes_;
  bool changes_known_ = false;   // changes_ holds changes_map_'s cells
  bool resend_changes_ = false;  // under mutex_: a subscriber came, send every cell
  tf2_ros::TransformBroadcaster tf_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  struct StampedPose {
    double stamp;
    Eigen::Isometry3d pose;
  };
  // Every frame's pose goes out (a planner wants them all); bounded, should ROS stall.
  std::deque<StampedPose> poses_;
  double last_stamp_ = 0;
  std::shared_ptr<const MapCloud> map_;
  UpEvidence up_;  // given with map_
  // The publishing thread's own: when the next grid may go out, the last map sent without its
  // grid (throttled), and where up and the floor came from (logged when it changes).
  double next_grid_at_ = 0.0;  // steady-clock seconds
  struct MapWithoutGrid {
    std::shared_ptr<const MapCloud> map;
    UpEvidence up;
    double stamp = 0.0;
  };
  MapWithoutGrid grid_behind_;
  std::string last_ground_;
  std::atomic<bool> map_pending_{false};
  std::atomic<double> next_map_at_{0.0};  // steady-clock seconds
  bool stop_ = false;
  std::atomic<std::uint64_t> maps_published_{0};
  std::thread thread_;
  std::unique_ptr<SessionPublisher> session_;
};

}  // namespace rgbdmap
