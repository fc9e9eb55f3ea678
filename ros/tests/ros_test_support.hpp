#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <memory>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace rgbdmap::test {

// A bag written once per build from a shared TUM folder by rgbdmap-tum2bag, in TUM's topic
// layout, named like TUM's bags (so that the folder's preset applies): tests/tmp/bags/<name>.bag.
// `tum_name` may also be a folder's path (a synthetic sequence): the bag is named after it.
// `options` are tum2bag's ("--depth16"); bags with different options get different files.
std::string sharedBag(const std::string& tum_name, const std::string& options = "",
                      const std::string& suffix = "");

// A roscore of the test's own on 127.0.0.1 at a free port; this process and every child started
// afterwards find it through ROS_MASTER_URI/ROS_IP (set here). Stopped by the destructor.
class Roscore {
 public:
  explicit Roscore(const std::string& log_dir);
  ~Roscore();
  const std::string& uri() const { return uri_; }

 private:
  std::string uri_;
  std::unique_ptr<Process> process_;
};

// How a bag is played into a node, and how the node takes it.
enum class Pace {
  // At the recorded rate, into a live node, as a camera sends: a node that falls behind drops
  // frames, and how many depends on the machine (bench/ros_node_drops.sh). For tests of what a
  // live node does, not of what it maps.
  kRecorded,
  // Into a lossless node (~lossless), the player waiting for it (rgbdmap-play, by the node's
  // ~intake): at the recorded rate when the node keeps up, slower when it does not, and
  // nothing dropped either way. For tests that judge the map.
  kNode,
};

// rgbdmap_node's command line writing into `dir` (map.pcd, stats.json; maps every second), in
// namespace `ns` with its own map frame (ns/map) when given; lossless for Pace::kNode.
std::vector<std::string> nodeArgs(const std::string& dir, const std::string& ns,
                                  Pace pace = Pace::kRecorded);
// The bag played once the node subscribed (no image lost to a late connection), at `pace` (the
// node must have been started with it); `ns` prefixes the topics, as for a second robot.
std::unique_ptr<Process> play(const std::string& bag, const std::string& ns, const std::string& log,
                              Pace pace = Pace::kRecorded);
// The node took every image played: after the bag ends its last images are paired, and the
// camera is reported silent (the pipeline checkpoints and waits for it).
bool waitUntilSilent(const std::string& node_log);
// What a lossless node must have done before its map is judged, whatever the machine's speed:
// taken each of the bag's `pairs` pairs of images, none lost on the way or dropped (from the
// line its node logs when the images stop: also for a node killed afterwards) ...
void expectEveryPairTaken(const std::string& node_log, std::size_t pairs);
// ... and, from its counters at exit, mapped each one (none dropped from the queue, none
// skipped) and made a map piece of every keyframe for its session stream.
void expectEveryFrameMapped(const std::string& stats_path, std::size_t pairs);

// A test with a roscore of its own (in a fresh folder, freshDir()), this process a ROS node
// ("rgbdmap_test_consumer") spinning on two threads.
class RosTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;
  std::string dir_;
  std::unique_ptr<Roscore> core_;
  std::unique_ptr<ros::NodeHandle> nh_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
};

std::string nodeBinary();
std::string mergerBinary();
std::string tum2bagBinary();
std::string playBinary();

}  // namespace rgbdmap::test
