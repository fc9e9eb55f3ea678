#pragma once

#include <memory>
#include <string>

#include "test_support.hpp"

namespace rgbdmap::test {

// A bag written once per build from a shared TUM folder by rgbdmap-tum2bag, in TUM's topic
// layout, named like TUM's bags (so that the folder's preset applies): tests/tmp/bags/<name>.bag.
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

std::string nodeBinary();
std::string tum2bagBinary();

}  // namespace rgbdmap::test
