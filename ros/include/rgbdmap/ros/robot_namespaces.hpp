#pragma once

#include <xmlrpcpp/XmlRpcValue.h>

#include <string>
#include <vector>

namespace rgbdmap {

// The fleet merger's ~robots: the namespaces its robots' nodes run in, the first one's frame the
// merged map's. Given as a rosparam list (["robot1", "robot2"], from a launch file or `rosparam
// set`) or as one string, which is what `_robots:=...` on a command line gives (roscpp keeps the
// text of a value that is not a number or a boolean): a YAML list ("[robot1, robot2]", names
// quoted or not) or names separated by spaces or commas ("robot1 robot2", "robot1,robot2").
// Returns each name absolute and without a trailing '/' ("/robot1"), in the order given. Throws
// InputError naming `parameter` (the resolved name, /rgbdmap_merger/robots) when a name is not
// a valid ROS name, a name is given twice, the list is not closed, or fewer than two are given.
std::vector<std::string> robotNamespaces(const XmlRpc::XmlRpcValue& value,
                                         const std::string& parameter);

}  // namespace rgbdmap
