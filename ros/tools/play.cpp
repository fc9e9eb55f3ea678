// rgbdmap-play: plays a bag into an rgbdmap_node that runs with ~lossless, at the pace the node
// maps it. Messages go out in the bag's order at its recorded rate at most; before one whose time
// is more than --lead seconds after the last image pair the node took (its ~intake), the player
// waits for the node, then goes on from there. So the node is never sent more than it holds:
// however slow or busy the machine, no image is lost on the way (ROS drops what a subscriber does
// not read in time) and the node maps every frame of the bag, as `rgbdmap --source rosbag:BAG
// --rate max` does. At the end the player stays until the node has received every image it sent
// (publish() only queues a message), then leaves: for the node, the end of the bag.
//
// (rosbag play --rate-control-topic was meant for pacing, but Noetic's player compares the
// node's stamps with a clock it advances only while it is ahead of the bag's timing: once a busy
// machine puts it behind, it holds back no more, and images are lost.)
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <spdlog/spdlog.h>
#include <std_msgs/UInt64MultiArray.h>

#include <CLI/CLI.hpp>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/runtime/exit_code.hpp"

namespace {

using namespace rgbdmap;

struct Options {
  std::string bag;
  std::string prefix;  // before every topic ("/robot1")
  std::string node;    // the node's name (default: PREFIX/rgbdmap)
  std::vector<std::string> topics;
  double lead = 0.5;  // seconds of the bag the player may be ahead of the node
};

// What the node reports on ~intake: images received, and the stamp of the last pair it took.
class Intake {
 public:
  void update(const std_msgs::UInt64MultiArray& m) {
    if (m.data.size() < 4) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      // Published from two of the node's threads: the newest of each count holds.
      received_ = std::max(received_, m.data[0] + m.data[1]);
      ros::Time taken;
      taken.fromNSec(m.data[3]);
      if (taken > taken_) taken_ = taken;
    }
    changed_.notify_all();
  }
  void start(const ros::Time& stamp) {
    std::lock_guard<std::mutex> lock(mutex_);
    taken_ = stamp;
  }
  // Waits until the node has taken a pair stamped `at_least` or later; returns whether it had
  // to wait.
  bool waitUntilTaken(const ros::Time& at_least, const std::function<bool()>& gone) {
    return waitUntil([&] { return taken_ >= at_least; }, gone);
  }
  // Waits until the node has received `images` images.
  void waitUntilReceived(std::uint64_t images, const std::function<bool()>& gone) {
    waitUntil([&] { return received_ >= images; }, gone);
  }

 private:
  bool waitUntil(const std::function<bool()>& done, const std::function<bool()>& gone) {
    std::unique_lock<std::mutex> lock(mutex_);
    const bool waited = !done();
    while (!done()) {
      if (!ros::ok()) return waited;
      if (gone()) throw InputError("the node stopped listening (is it running with ~lossless?)");
      changed_.wait_for(lock, std::chrono::milliseconds(100));
    }
    return waited;
  }

  std::mutex mutex_;
  std::condition_variable changed_;
  std::uint64_t received_ = 0;
  ros::Time taken_;
};

int play(const Options& o) {
  rosbag::Bag bag;
  try {
    bag.open(o.bag, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw InputError(o.bag + ": " + e.what());
  }
  rosbag::View view;
  if (o.topics.empty())
    view.addQuery(bag);
  else
    view.addQuery(bag, rosbag::TopicQuery(o.topics));
  if (view.size() == 0) throw InputError(o.bag + ": no message on the topics asked for");

  ros::NodeHandle nh;
  std::map<std::string, ros::Publisher> publishers;
  std::vector<std::string> images;  // the image topics, whose subscribers are waited for
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (publishers.count(c->topic)) continue;
    if (c->datatype == "sensor_msgs/Image") images.push_back(c->topic);
    // Deep queues: the lead, not the queue, bounds what waits for the node.
    ros::AdvertiseOptions advertise(o.prefix + c->topic, 1000, c->md5sum, c->datatype, c->msg_def);
    const auto latching = c->header->find("latching");
    advertise.latch = latching != c->header->end() && latching->second == "1";
    publishers[c->topic] = nh.advertise(advertise);
  }
  const std::string node = o.node.empty() ? o.prefix + "/rgbdmap" : o.node;
  Intake intake;
  ros::Subscriber progress = nh.subscribe<std_msgs::UInt64MultiArray>(
      node + "/intake", 10,
      [&intake](const std_msgs::UInt64MultiArray::ConstPtr& m) { intake.update(*m); });
  ros::AsyncSpinner spinner(1);
  spinner.start();

  // Every image goes to a subscriber: none is published before the node listens to each image
  // topic. (Other topics, camera_info, go out with them whether anyone listens or not.)
  if (images.empty()) throw InputError(o.bag + ": no image topic to play");
  std::string listed;
  for (const std::string& topic : images) listed += " " + o.prefix + topic;
  spdlog::info("{}: waiting for {} (with ~lossless) to subscribe to{}", o.bag, node, listed);
  for (bool all = false; !all && ros::ok(); ros::WallDuration(0.1).sleep()) {
    all = progress.getNumPublishers() > 0;
    for (const std::string& topic : images) all = all && publishers[topic].getNumSubscribers() > 0;
  }
  // A node that went away (killed) takes no more: the player stops instead of waiting for ever.
  const auto gone = [&] {
    for (const std::string& topic : images)
      if (publishers[topic].getNumSubscribers() == 0) return true;
    return false;
  };

  const ros::Time first = view.getBeginTime();
  intake.start(first);  // the first --lead seconds go out at once
  const ros::WallTime started = ros::WallTime::now();
  ros::WallDuration waited;  // for the node: the recorded timing resumes from where it waited
  std::size_t messages = 0;
  std::uint64_t images_sent = 0;
  for (const rosbag::MessageInstance& m : view) {
    if (!ros::ok()) break;
    const ros::WallTime due = started + waited + ros::WallDuration((m.getTime() - first).toSec());
    ros::WallTime::sleepUntil(due);
    const ros::WallTime before = ros::WallTime::now();
    if (intake.waitUntilTaken(m.getTime() - ros::Duration(o.lead), gone))
      waited += ros::WallTime::now() - before;
    publishers[m.getTopic()].publish(m);
    ++messages;
    if (m.getDataType() == "sensor_msgs/Image") ++images_sent;
  }
  intake.waitUntilReceived(images_sent, gone);
  spdlog::info("{}: {} messages played in {:.1f} s ({:.1f} s of them waiting for {})", o.bag,
               messages, (ros::WallTime::now() - started).toSec(), waited.toSec(), node);
  spinner.stop();
  return ros::ok() ? 0 : 130;
}

}  // namespace

int main(int argc, char** argv) {
  // Anonymous: several players (one per robot) run at once.
  ros::init(argc, argv, "rgbdmap_play", ros::init_options::AnonymousName);
  CLI::App app{"rgbdmap-play: a bag into an rgbdmap_node (~lossless), at the pace it maps"};
  Options o;
  app.add_option("bag", o.bag, "bag to play")->required();
  app.add_option("--prefix", o.prefix, "put before every topic (a robot's namespace: /robot1)");
  app.add_option("--node", o.node, "the node's name (default: PREFIX/rgbdmap)");
  app.add_option("--topics", o.topics,
                 "only these topics of the bag (its image topics must be the node's colour and "
                 "depth: choose them here when it has others)");
  app.add_option("--lead", o.lead, "seconds of the bag the player may be ahead of the node")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  return rgbdmap::runGuarded([&] { return play(o); });
}
