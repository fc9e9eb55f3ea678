#include "ros_test_support.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <csignal>
#include <cstdlib>
#include <filesystem>

namespace rgbdmap::test {
namespace {

// A port nobody listens on now: the kernel's choice for an ephemeral bind, released at once.
int freePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  int port = -1;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0)
    port = ntohs(addr.sin_port);
  ::close(fd);
  return port;
}

}  // namespace

void RosTest::SetUp() {
  dir_ = freshDir();
  core_ = std::make_unique<Roscore>(dir_);
  int argc = 0;
  ros::init(argc, nullptr, "rgbdmap_test_consumer", ros::init_options::NoSigintHandler);
  nh_ = std::make_unique<ros::NodeHandle>();
  spinner_ = std::make_unique<ros::AsyncSpinner>(2);
  spinner_->start();
}

void RosTest::TearDown() {
  spinner_->stop();
  nh_.reset();
  ros::shutdown();
  core_.reset();
}

std::string nodeBinary() { return RGBDMAP_NODE_BINARY; }
std::string mergerBinary() { return RGBDMAP_MERGER_BINARY; }
std::string tum2bagBinary() { return RGBDMAP_TUM2BAG_BINARY; }
std::string playBinary() { return RGBDMAP_PLAY_BINARY; }

std::vector<std::string> nodeArgs(const std::string& dir, const std::string& ns, Pace pace) {
  std::vector<std::string> args = {nodeBinary(), "_out:=" + dir + "/map.pcd",
                                   "_stats:=" + dir + "/stats.json", "_map_interval:=1"};
  if (!ns.empty()) {
    args.push_back("__ns:=" + ns);
    args.push_back("_map_frame:=" + ns + "/map");
  }
  if (pace == Pace::kNode) args.push_back("_lossless:=true");
  return args;
}

std::unique_ptr<Process> play(const std::string& bag, const std::string& ns, const std::string& log,
                              Pace pace) {
  const std::string p = ns.empty() ? "" : "/" + ns;
  // rgbdmap-play waits for the node's ~intake (half a second of the bag ahead at most);
  // rosbag play at the recorded rate waits for nothing once the node subscribed.
  std::vector<std::string> args =
      pace == Pace::kNode
          ? std::vector<std::string>{playBinary(), "--lead", "0.5"}
          : std::vector<std::string>{"/usr/bin/rosbag", "play", "-q", "--wait-for-subscribers"};
  if (!ns.empty()) args.push_back("--prefix=" + p);
  args.push_back(bag);  // before --topics, which takes every argument after it
  for (const char* t :
       {"--topics", "/camera/rgb/image_color", "/camera/depth/image", "/camera/rgb/camera_info"})
    args.push_back(t);
  return std::make_unique<Process>(args, log);
}

bool waitUntilSilent(const std::string& node_log) {
  return waitUntil(
      [&] {
        return readFile(node_log).find("camera stopped delivering frames") != std::string::npos;
      },
      60);
}

namespace {

// The numbers in `text` from `marker` on to the end of its line, in order.
std::vector<double> numbersAfter(const std::string& text, const std::string& marker) {
  std::vector<double> numbers;
  const std::size_t at = text.rfind(marker);
  if (at == std::string::npos) return numbers;
  const std::size_t end = std::min(text.find('\n', at), text.size());
  for (std::size_t i = at + marker.size(); i < end; ++i) {
    if (!std::isdigit(static_cast<unsigned char>(text[i]))) continue;
    char* after = nullptr;
    numbers.push_back(std::strtod(text.c_str() + i, &after));
    i = static_cast<std::size_t>(after - text.c_str());
  }
  return numbers;
}

}  // namespace

void expectEveryPairTaken(const std::string& node_log, std::size_t pairs) {
  const std::string log = readFile(node_log);
  // "camera silent after C colour and D depth images (L colour lost before the node): P pairs,
  // B dropped in the node's buffer, U images unpaired" (the last such line).
  const std::vector<double> n = numbersAfter(log, "camera silent after ");
  ASSERT_EQ(n.size(), 6u) << node_log << ":\n" << log;
  const double expected = static_cast<double>(pairs);
  EXPECT_EQ(n[3], expected) << "pairs taken, of the bag's " << pairs << ":\n" << log;
  EXPECT_EQ(n[2], 0) << "colour images lost before the node:\n" << log;
  EXPECT_EQ(n[4], 0) << "pairs dropped in the node's buffer:\n" << log;
}

void expectEveryFrameMapped(const std::string& stats_path, std::size_t pairs) {
  const std::string stats = readFile(stats_path);
  ASSERT_FALSE(stats.empty()) << stats_path;
  EXPECT_EQ(jsonNumber(stats, "paired"), static_cast<double>(pairs)) << stats;
  EXPECT_EQ(jsonNumber(stats, "frames_processed"), static_cast<double>(pairs)) << stats;
  for (const char* none : {"color_lost", "buffer_dropped", "frames_dropped", "frames_skipped",
                           "session_keyframes_dropped"})
    EXPECT_EQ(jsonNumber(stats, none), 0) << none << " in " << stats;
}

std::string sharedBag(const std::string& tum_name, const std::string& options,
                      const std::string& suffix) {
  namespace fs = std::filesystem;
  const std::string folder = std::string(RGBDMAP_TEST_TMP) + "/bags";
  fs::create_directories(folder);
  // A folder's path (a synthetic sequence) or the name of a shared TUM folder.
  const bool is_path = tum_name.find('/') != std::string::npos;
  const std::string name = is_path ? fs::path(tum_name).filename().string() : tum_name;
  const std::string path = folder + "/" + name + suffix + ".bag";
  if (fs::exists(path)) return path;
  // Written beside and renamed: tests running at the same time never see half a bag.
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  std::string output;
  const int code = run(
      tum2bagBinary() + " " + options + " " + (is_path ? tum_name : tumDir(tum_name)) + " " + tmp,
      &output);
  EXPECT_EQ(code, 0) << output;
  // A failed conversion leaves no bag behind for the next test to take as good.
  if (code == 0)
    fs::rename(tmp, path);
  else
    fs::remove(tmp);
  return path;
}

Roscore::Roscore(const std::string& log_dir) {
  const int port = freePort();
  uri_ = "http://127.0.0.1:" + std::to_string(port);
  ::setenv("ROS_MASTER_URI", uri_.c_str(), 1);
  ::setenv("ROS_IP", "127.0.0.1", 1);
  ::unsetenv("ROS_HOSTNAME");
  ::setenv("ROS_HOME", log_dir.c_str(), 1);  // its logs stay with the test's files
  const std::string log = log_dir + "/roscore.log";
  process_ = std::make_unique<Process>(
      std::vector<std::string>{"/usr/bin/roscore", "-p", std::to_string(port)}, log);
  // Ready once /rosout runs (roslaunch logs it after the master is up).
  const bool up = waitUntil(
      [&] { return readFile(log).find("started core service [/rosout]") != std::string::npos; },
      60);
  EXPECT_TRUE(up) << "roscore did not start:\n" << readFile(log);
}

Roscore::~Roscore() {
  // SIGINT lets roslaunch stop the master and rosout it started; SIGKILL would orphan them.
  process_->signal(SIGINT);
  if (process_->wait(20) < 0) ADD_FAILURE() << "roscore did not stop on SIGINT";
}

}  // namespace rgbdmap::test
