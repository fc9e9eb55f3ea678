#include "rgbdmap/ros/ros_publisher.hpp"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstring>
#include <utility>

#include "rgbdmap/ros/cloud_message.hpp"

namespace rgbdmap {
namespace {

constexpr std::size_t kMaxPoses = 256;

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

ros::Time rosTime(double seconds) {
  ros::Time t;
  if (seconds > 0) t.fromSec(seconds);
  return t;
}

}  // namespace

RosPublisher::RosPublisher(ros::NodeHandle& private_nh, Options options)
    : options_(std::move(options)) {
  // Latched: a consumer that subscribes later (another machine, a screen) still gets the map.
  map_pub_ = private_nh.advertise<sensor_msgs::PointCloud2>("map", 1, true);
  // Not latched: the last changes alone would be part of a map. When someone subscribes, every
  // cell of the last map goes out again (on this publisher's thread: a building's map takes a
  // second to group, which ROS's callback threads must not wait for), then what changes.
  changes_pub_ = private_nh.advertise<sensor_msgs::PointCloud2>(
      "map_changes", 4, [this](const ros::SingleSubscriberPublisher&) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          resend_changes_ = true;
        }
        wake_.notify_one();
      });
  pose_pub_ = private_nh.advertise<geometry_msgs::PoseStamped>("pose", 10);
  if (options_.grid_interval >= 0.0)
    grid_pub_ = private_nh.advertise<nav_msgs::OccupancyGrid>("grid", 1, true);
  if (options_.session.interval > 0.0)
    session_ = std::make_unique<SessionPublisher>(private_nh, options_.session);
  thread_ = std::thread([this] { run(); });
}

void RosPublisher::attachGraph(const LoopCloser* graph, const CameraIntrinsics& camera) {
  if (session_) session_->attach(graph, camera);
}

void RosPublisher::publishKeyframe(const Frame& keyframe) {
  if (session_) session_->addKeyframe(keyframe);
}

RosPublisher::~RosPublisher() { finish(); }

void RosPublisher::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stop_) return;
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void RosPublisher::publishFrame(const Frame& frame, const PublishedStatus& /*status*/) {
  if (!frame.has_pose) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (poses_.size() >= kMaxPoses) poses_.pop_front();
    poses_.push_back({frame.timestamp, frame.pose});
    last_stamp_ = frame.timestamp;
  }
  wake_.notify_one();
}

bool RosPublisher::wantsMap() const { return !map_pending_.load() && now() >= next_map_at_.load(); }

void RosPublisher::publishMap(std::shared_ptr<const MapCloud> map) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    map_ = std::move(map);
    map_pending_.store(true);
  }
  wake_.notify_one();
}

void RosPublisher::publishUp(const UpEvidence& evidence) {
  std::lock_guard<std::mutex> lock(mutex_);
  up_ = evidence;
}

void RosPublisher::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stop_ || !poses_.empty() || map_ || resend_changes_; });
    while (!poses_.empty()) {
      const StampedPose p = poses_.front();
      poses_.pop_front();
      lock.unlock();
      sendPose(p.stamp, p.pose);
      lock.lock();
    }
    if (map_) {
      const std::shared_ptr<const MapCloud> map = std::move(map_);
      map_.reset();
      const double stamp = last_stamp_;
      const UpEvidence up = up_;
      const bool everything = std::exchange(resend_changes_, false);
      lock.unlock();
      sendMap(*map, stamp);
      sendChanges(map, stamp, everything);
      if (options_.grid_interval >= 0.0) {
        if (now() >= next_grid_at_) {
          sendGrid(*map, up, stamp);
          next_grid_at_ = now() + options_.grid_interval;
          grid_behind_ = {};
        } else {
          grid_behind_ = {map, up, stamp};  // drawn at the end if no later grid replaces it
        }
      }
      next_map_at_.store(now() + options_.map_interval);
      map_pending_.store(false);
      lock.lock();
    }
    if (std::exchange(resend_changes_, false) && changes_map_) {
      lock.unlock();
      sendChanges(changes_map_, changes_stamp_, true);
      lock.lock();
    }
    if (stop_ && poses_.empty() && !map_) break;
  }
  // The last map's grid is the one that stays latched.
  if (grid_behind_.map) {
    lock.unlock();
    sendGrid(*grid_behind_.map, grid_behind_.up, grid_behind_.stamp);
  }
}

void RosPublisher::sendPose(double stamp, const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.rotation());
  const Eigen::Vector3d t = pose.translation();
  geometry_msgs::PoseStamped msg;
  msg.header.stamp = rosTime(stamp);
  msg.header.frame_id = options_.map_frame;
  msg.pose.position.x = t.x();
  msg.pose.position.y = t.y();
  msg.pose.position.z = t.z();
  msg.pose.orientation.x = q.x();
  msg.pose.orientation.y = q.y();
  msg.pose.orientation.z = q.z();
  msg.pose.orientation.w = q.w();
  pose_pub_.publish(msg);

  geometry_msgs::TransformStamped tf;
  tf.header = msg.header;
  tf.child_frame_id = options_.camera_frame;
  tf.transform.translation.x = t.x();
  tf.transform.translation.y = t.y();
  tf.transform.translation.z = t.z();
  tf.transform.rotation = msg.pose.orientation;
  tf_.sendTransform(tf);
}

void RosPublisher::sendGrid(const MapCloud& map, const UpEvidence& up, double stamp) {
  GroundFrame ground;
  OccupancyGrid grid;
  try {
    ground = GroundFrame::resolve(map, up, options_.up);
    grid = OccupancyGrid::build(map, ground, options_.grid);
  } catch (const std::exception& e) {
    spdlog::error("grid not published: {}", e.what());
    return;
  }
  if (grid.width == 0) return;  // nothing between the floor and the robot's height yet
  if (ground.sources() != last_ground_) {
    spdlog::info("grid: {}", ground.describe());
    last_ground_ = ground.sources();
  }
  nav_msgs::OccupancyGrid msg;
  msg.header.stamp = rosTime(stamp);
  msg.header.frame_id = options_.map_frame;
  msg.info.map_load_time = msg.header.stamp;
  msg.info.resolution = static_cast<float>(grid.resolution);
  msg.info.width = static_cast<std::uint32_t>(grid.width);
  msg.info.height = static_cast<std::uint32_t>(grid.height);
  const Eigen::Quaterniond q(grid.map_from_grid.linear());
  const Eigen::Vector3d t = grid.map_from_grid.translation();
  msg.info.origin.position.x = t.x();
  msg.info.origin.position.y = t.y();
  msg.info.origin.position.z = t.z();
  msg.info.origin.orientation.x = q.x();
  msg.info.origin.orientation.y = q.y();
  msg.info.origin.orientation.z = q.z();
  msg.info.origin.orientation.w = q.w();
  msg.data = grid.cells;  // row-major from the origin, -1 unknown, 0 free, 100 occupied
  grid_pub_.publish(msg);
}

void RosPublisher::sendMap(const MapCloud& map, double stamp) {
  map_pub_.publish(toCloudMessage(map, options_.map_frame, stamp, options_.map_max_points));
  maps_published_.fetch_add(1);
}

void RosPublisher::sendChanges(const std::shared_ptr<const MapCloud>& map, double stamp,
                               bool everything) {
  changes_map_ = map;
  changes_stamp_ = stamp;
  if (changes_pub_.getNumSubscribers() == 0) {
    changes_known_ = false;  // nobody to tell: whoever subscribes gets every cell
    return;
  }
  const MapCells cells = MapCells::of(*map);
  // Removed cells are named against the last map grouped, even when all of this one is sent:
  // a consumer that had that map must lose them.
  const MapChanges::Change change = changes_.next(cells, everything || !changes_known_);
  changes_known_ = true;
  if (change.changed.empty() && change.removed.empty()) return;
  changes_pub_.publish(toCellChangesMessage(*map, cells, change, options_.map_frame, stamp));
  if (everything)
    spdlog::info("{}: every cell of the map sent ({} points, {} subscribers)",
                 changes_pub_.getTopic(), map->size(), changes_pub_.getNumSubscribers());
}

}  // namespace rgbdmap
