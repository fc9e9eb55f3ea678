// rgbdmap_merger: one map of a fleet. Subscribes to the session stream of every robot in ~robots
// (the namespaces their rgbdmap_node runs in: graph, places and map pieces), places the robots in
// the first one's frame by the places they share, fuses their map pieces at the merged poses, and
// publishes the merged map (/merged/map, latched, at most every ~map_interval s) and TF
// ~merged_frame -> <robot>/map for every placed robot; ~save_map writes the merged map and
// session. Robots never wait for it.
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <spdlog/spdlog.h>
#include <std_msgs/UInt8MultiArray.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <thread>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/map_files/pcd_file.hpp"
#include "rgbdmap/ros/cloud_message.hpp"
#include "rgbdmap/ros/robot_namespaces.hpp"
#include "rgbdmap/runtime/exit_code.hpp"
#include "rgbdmap/sessions/fleet_merger.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/slam/motion.hpp"

namespace {

using namespace rgbdmap;

struct Settings {
  std::vector<std::string> robots;  // namespaces, without a trailing '/'
  std::string out = "merged.pcd";   // with MERGED.session beside it
  std::string merged_frame = "merged_map";
  std::string config = "default";
  double map_interval = 2.0;
  double merge_interval = 1.0;
  double voxel = 0.0;  // the merged map's; 0: the configuration's map.voxel_size
  bool resume = true;  // pick up from the session saved at ~out
};

// ~robots: a rosparam list, or one string (a YAML list, or names separated by spaces or commas).
std::vector<std::string> robotsParam(const ros::NodeHandle& pnh) {
  XmlRpc::XmlRpcValue value;
  if (!pnh.getParam("robots", value)) value.clear();  // invalid: none given
  return robotNamespaces(value, pnh.resolveName("robots"));
}

Settings readSettings(const ros::NodeHandle& pnh) {
  Settings s;
  s.robots = robotsParam(pnh);
  pnh.param("out", s.out, s.out);
  pnh.param("merged_frame", s.merged_frame, s.merged_frame);
  pnh.param("config", s.config, s.config);
  pnh.param("map_interval", s.map_interval, s.map_interval);
  pnh.param("merge_interval", s.merge_interval, s.merge_interval);
  pnh.param("voxel", s.voxel, s.voxel);
  pnh.param("resume", s.resume, s.resume);
  if (!(s.merge_interval > 0) || !(s.map_interval >= 0) || !(s.voxel >= 0))
    throw InputError("parameters " + pnh.resolveName("merge_interval") + ", " +
                     pnh.resolveName("map_interval") + " and " + pnh.resolveName("voxel") +
                     ": must be > 0, >= 0 and >= 0");
  return s;
}

std::string frameOf(const std::string& robot) { return robot.substr(1) + "/map"; }

std::string sessionPathOf(const Settings& s) {
  return (std::filesystem::path(s.out).replace_extension(".session")).string();
}

// A merger restarted with the session it saved picks up from it: the robots' streams as they
// were (a robot gone since keeps its part), then what the robots send again.
// Returns whether it did.
bool resumeFrom(FleetMerger& merger, const Settings& s, const ros::NodeHandle& pnh) {
  const std::string path = sessionPathOf(s);
  std::error_code ec;
  if (!s.resume || !std::filesystem::exists(path, ec)) return false;
  Session saved;
  try {
    saved = readSession(path);
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + " (the merged session to pick up from; move it away " +
                     "or set " + pnh.resolveName("resume") + ":=false to start afresh)");
  }
  const std::size_t runs = merger.resume(saved, path);
  merger.merge();
  std::size_t placed = 0;
  for (const FleetMerger::Robot& r : merger.robots()) placed += r.placed ? 1 : 0;
  spdlog::info("merger: picked up from {}: {} of its {} runs, {} robots placed", path, runs,
               saved.streams.size(), placed);
  return runs > 0;
}

// The merged map and session, written beside each other; the answer says where or why not.
bool save(FleetMerger& merger, const Settings& s, std::string& message) {
  const MapCloud map = merger.map();
  const Session session = merger.session();
  const std::string session_path = sessionPathOf(s);
  std::string error;
  if (session.graph.keyframes.empty()) {
    message = "nothing to save: no robot's stream has arrived";
    return false;
  }
  if (!writePcdAtomically(map, s.out, error) || !writeSession(session, session_path, error)) {
    message = error;
    return false;
  }
  // The merged graph's keyframe trajectory beside the map: every robot's keyframes, one frame.
  const std::string keyframes =
      (std::filesystem::path(s.out).replace_extension("").string()) + "_keyframes.txt";
  try {
    graphTrajectory(session).save(keyframes);
  } catch (const std::exception& e) {
    message = e.what();
    return false;
  }
  message =
      s.out + " (" + std::to_string(map.size()) + " points), " + session_path + " and " + keyframes;
  return true;
}

// What the merger cost, for its whole run: the merges (one thread's CPU time), the place pairs
// each robot's places were compared with, and the process's CPU time (merges, the merged map's
// fusion and publishing, ROS).
void reportWork(const FleetMerger& merger, double started) {
  const FleetMerger::Work work = merger.work();
  const std::vector<FleetMerger::Robot> robots = merger.robots();
  std::string compared;
  for (const FleetMerger::Robot& r : robots)
    compared += (compared.empty() ? "" : ", ") + r.name + " " + std::to_string(r.compared);
  const double cpu = static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
  const double minutes = std::max(1e-9, (steadySeconds() - started) / 60.0);
  spdlog::info(
      "merger: {} merges ({:.1f} s of CPU), {} maps; place pairs compared: {}; CPU {:.1f} s in "
      "{:.1f} min ({:.2f} s per robot and minute)",
      work.merges, work.merge_seconds, work.maps, compared, cpu, minutes,
      cpu / minutes / static_cast<double>(std::max<std::size_t>(1, robots.size())));
}

void report(const std::vector<FleetMerger::Robot>& robots) {
  for (const FleetMerger::Robot& r : robots)
    if (!r.placed)
      spdlog::info(
          "merger: {} not placed: {} keyframes and {} places received, none shared with "
          "a placed robot",
          r.name, r.keyframes, r.places);
}

// Wakes the merging loop when records arrive.
class Arrivals {
 public:
  void notify() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      pending_ = true;
    }
    wake_.notify_one();
  }
  void waitFor(double seconds) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return pending_; });
    pending_ = false;
  }

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  bool pending_ = false;
};

// TF from the merged frame to each placed robot's map frame.
void broadcastPlacements(const std::vector<FleetMerger::Robot>& robots,
                         const std::string& merged_frame, tf2_ros::TransformBroadcaster& tf) {
  const ros::Time now = ros::Time::now();
  for (const FleetMerger::Robot& r : robots) {
    if (!r.placed) continue;
    geometry_msgs::TransformStamped t;
    t.header.stamp = now;
    t.header.frame_id = merged_frame;
    t.child_frame_id = frameOf(r.name);
    const Eigen::Quaterniond q(r.transform.linear());
    t.transform.translation.x = r.transform.translation().x();
    t.transform.translation.y = r.transform.translation().y();
    t.transform.translation.z = r.transform.translation().z();
    t.transform.rotation.x = q.x();
    t.transform.rotation.y = q.y();
    t.transform.rotation.z = q.z();
    t.transform.rotation.w = q.w();
    tf.sendTransform(t);
  }
}

int runMerger() {
  const double started = steadySeconds();
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const Settings s = readSettings(pnh);
  Config config;
  config.loadPreset(s.config);
  if (s.voxel > 0) config.map.voxel_size = s.voxel;
  FleetMerger merger(s.robots, config);
  Arrivals arrived;

  std::atomic<bool> resend_wanted[64];
  if (s.robots.size() > 64) throw InputError(pnh.resolveName("robots") + ": at most 64 robots");
  for (auto& w : resend_wanted) w.store(true);  // a merger that starts late asks for everything
  std::vector<ros::Subscriber> subscribers;
  for (std::size_t i = 0; i < s.robots.size(); ++i) {
    for (const char* topic :
         {"/rgbdmap/session/graph", "/rgbdmap/session/places", "/rgbdmap/session/pieces"}) {
      const std::string name = s.robots[i] + topic;
      subscribers.push_back(nh.subscribe<std_msgs::UInt8MultiArray>(
          name, 1000, [&, i, name](const std_msgs::UInt8MultiArray::ConstPtr& m) {
            try {
              const std::string record(m->data.begin(), m->data.end());
              if (merger.receive(i, record, name) == SessionAssembler::Result::kGap)
                resend_wanted[i].store(true);
              arrived.notify();
            } catch (const InputError& e) {
              spdlog::warn("merger: {} (record ignored)", e.what());
            }
          }));
    }
  }
  ros::Publisher map_pub = nh.advertise<sensor_msgs::PointCloud2>("/merged/map", 1, true);
  tf2_ros::TransformBroadcaster tf;
  ros::ServiceServer save_map =
      pnh.advertiseService<std_srvs::Trigger::Request, std_srvs::Trigger::Response>(
          "save_map", [&](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
            merger.merge();
            response.success = save(merger, s, response.message);
            report(merger.robots());
            return true;
          });
  // After the topics and the service are set up with the master (a Ctrl-C while roscpp still
  // talks to it left the merger retrying for ever), before the callbacks run.
  const bool resumed = resumeFrom(merger, s, pnh);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  spdlog::info(
      "merger: robots {}; publishing /merged/map and TF {} -> <robot>/map; service {}",
      [&] {
        std::string all;
        for (const auto& r : s.robots) all += (all.empty() ? "" : " ") + r;
        return all;
      }(),
      s.merged_frame, save_map.getService());

  // The merged map on a thread of its own: fusing new pieces takes time the merges (and so the
  // TF a robot is placed by) should not wait for.
  std::atomic<bool> map_stale{resumed}, stopping{false};
  std::thread map_thread([&] {
    while (!stopping.load()) {
      // Fused and published only while someone listens: the fusion is most of the merger's
      // work, and a save fuses what is left. (Latched: whoever subscribes later gets the last
      // one, and a newer one once anything changed.)
      if (map_pub.getNumSubscribers() > 0 && map_stale.exchange(false))
        map_pub.publish(toCloudMessage(merger.map(), s.merged_frame, ros::Time::now().toSec()));
      ros::WallDuration(std::max(0.05, s.map_interval)).sleep();
    }
  });
  while (ros::ok()) {
    for (std::size_t i = 0; i < s.robots.size(); ++i) {
      if (!resend_wanted[i].exchange(false)) continue;
      const std::string service = s.robots[i] + "/rgbdmap/session/resend";
      std_srvs::Trigger call;
      // Not there yet (the robot starts later): asked again next time.
      if (!ros::service::exists(service, false) || !ros::service::call(service, call))
        resend_wanted[i].store(true);
    }
    const bool changed = merger.merge();
    broadcastPlacements(merger.robots(), s.merged_frame, tf);
    if (changed) map_stale.store(true);
    // Until records arrive (a merge costs what arrived since the last: a place shared is placed
    // within a second), and at least every ~merge_interval s for TF.
    arrived.waitFor(s.merge_interval);
  }
  stopping.store(true);
  map_thread.join();
  // Stopped (Ctrl-C): the merged map and session as they are.
  merger.merge();
  std::string message;
  if (save(merger, s, message))
    spdlog::info("merger: saved {}", message);
  else
    spdlog::warn("merger: {}", message);
  report(merger.robots());
  reportWork(merger, started);
  spinner.stop();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::default_logger_raw();
  // On a machine it shares with robots' nodes, the merger's work (merges, the merged map's
  // fusion) waits for theirs: a node that drops frames tracks worse, and robots never wait for
  // the merger. Every thread started from here on inherits it.
  rgbdmap::giveWayToTracking();
  ros::init(argc, argv, "rgbdmap_merger");
  return rgbdmap::runGuarded([&] { return runMerger(); });
}
