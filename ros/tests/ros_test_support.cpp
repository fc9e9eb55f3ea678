#include "ros_test_support.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

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

std::string nodeBinary() { return RGBDMAP_NODE_BINARY; }
std::string tum2bagBinary() { return RGBDMAP_TUM2BAG_BINARY; }

std::string sharedBag(const std::string& tum_name, const std::string& options,
                      const std::string& suffix) {
  namespace fs = std::filesystem;
  const std::string folder = std::string(RGBDMAP_TEST_TMP) + "/bags";
  fs::create_directories(folder);
  const std::string path = folder + "/" + tum_name + suffix + ".bag";
  if (fs::exists(path)) return path;
  // Written beside and renamed: tests running at the same time never see half a bag.
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  std::string output;
  const int code =
      run(tum2bagBinary() + " " + options + " " + tumDir(tum_name) + " " + tmp, &output);
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
