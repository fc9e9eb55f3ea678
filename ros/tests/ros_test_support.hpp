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

// rgbdmap_node's command line writing into `dir` (map.pcd, stats.json; maps every second), in
// namespace `ns` with its own map frame (ns/map) when given.
std::vector<std::string> nodeArgs(const std::string& dir, const std::string& ns);
// rosbag play at the recorded rate, once the node subscribed (no image lost to a late
// connection); `ns` prefixes the topics, as for a second robot.
std::unique_ptr<Process> play(const std::string& bag, const std::string& ns,
                              const std::string& log);
// The node took every image played: after the bag ends its last images are paired, and the
// camera is reported silent (the pipeline checkpoints and waits for it).
bool waitUntilSilent(const std::string& node_log);

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

}  // namespace rgbdmap::test
