// The merger's ~robots in each spelling ROS users give it: a rosparam list (a launch file's
// <rosparam>, `rosparam set`) and the string `_robots:=...` gives (roscpp keeps the text of a
// value that is not a number): a YAML list, or names separated by spaces or commas.
#include <gtest/gtest.h>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/ros/robot_namespaces.hpp"

namespace rgbdmap {
namespace {

const std::string kParameter = "/rgbdmap_merger/robots";
const std::vector<std::string> kTwo = {"/robot1", "/robot2"};

std::vector<std::string> fromString(const std::string& text) {
  return robotNamespaces(XmlRpc::XmlRpcValue(text), kParameter);
}

XmlRpc::XmlRpcValue list(const std::vector<XmlRpc::XmlRpcValue>& items) {
  XmlRpc::XmlRpcValue value;
  value.setSize(static_cast<int>(items.size()));
  for (std::size_t i = 0; i < items.size(); ++i) value[static_cast<int>(i)] = items[i];
  return value;
}

// The message of the InputError `read` throws ("" when it throws none).
template <class Read>
std::string refusal(Read read) {
  try {
    read();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(RobotNamespaces, ARosparamList) {
  EXPECT_EQ(robotNamespaces(list({std::string("robot1"), std::string("robot2")}), kParameter),
            kTwo);
  // Absolute already, or with a trailing '/': the same namespaces; the order is kept (the first
  // robot's frame is the merged map's).
  EXPECT_EQ(robotNamespaces(list({std::string("/robot2/"), std::string("/robot1")}), kParameter),
            (std::vector<std::string>{"/robot2", "/robot1"}));
}

TEST(RobotNamespaces, AYamlListInAString) {
  EXPECT_EQ(fromString("[robot1, robot2]"), kTwo);  // what failed: "Character [[] ..."
  EXPECT_EQ(fromString("['robot1', \"robot2\"]"), kTwo);
  EXPECT_EQ(fromString(" [ /robot1,robot2/ ] "), kTwo);
  EXPECT_EQ(fromString("[fleet/robot1, fleet/robot2, robot_3]"),
            (std::vector<std::string>{"/fleet/robot1", "/fleet/robot2", "/robot_3"}));
}

TEST(RobotNamespaces, NamesSeparatedBySpacesOrCommas) {
  EXPECT_EQ(fromString("robot1 robot2"), kTwo);
  EXPECT_EQ(fromString("robot1,robot2"), kTwo);
  EXPECT_EQ(fromString("robot1, robot2\trobot3"),
            (std::vector<std::string>{"/robot1", "/robot2", "/robot3"}));
}

// Bad input: one message naming the parameter and what is wrong, never a roscpp exception from
// deep inside a subscribe.
TEST(RobotNamespaces, BadInputIsOneClearMessageNamingTheParameter) {
  const std::string prefix = "parameter " + kParameter + ": ";
  EXPECT_EQ(
      refusal([] { fromString("[robot1, robot-2]"); }).rfind(prefix + "'robot-2' is not a", 0), 0u);
  EXPECT_EQ(refusal([] { fromString("robot1 2robot"); }).rfind(prefix + "'2robot' is not a", 0),
            0u);
  EXPECT_EQ(refusal([] { fromString("robot1 robot2//x"); }).rfind(prefix + "'robot2//x'", 0), 0u);
  EXPECT_EQ(refusal([] { fromString("['robot1', 'robot 2']"); }).rfind(prefix + "'robot 2'", 0),
            0u);
  EXPECT_EQ(refusal([] { fromString("[robot1, robot2"); }),
            prefix + "the list \"[robot1, robot2\" is not closed by ']'");
  EXPECT_EQ(refusal([] { fromString("['robot1, robot2]"); }).rfind(prefix + "a quote in", 0), 0u);
  EXPECT_EQ(refusal([] { fromString("robot1 /robot1/"); }), prefix + "/robot1 is listed twice");
  EXPECT_EQ(refusal([] { fromString("[robot1, '']"); }).rfind(prefix + "'' is not a", 0), 0u);
  // Fewer than two, or none: what is wanted, with the spellings.
  for (const char* text : {"robot1", "[]", ""})
    EXPECT_NE(refusal([&] { fromString(text); }).find(prefix + "the namespaces of two robots"),
              std::string::npos)
        << text;
  EXPECT_NE(refusal([] {
              robotNamespaces(XmlRpc::XmlRpcValue(), kParameter);
            }).find(prefix + "the namespaces of two robots"),
            std::string::npos);
  // Not names: a number, a list holding a number.
  EXPECT_EQ(refusal([] {
              robotNamespaces(XmlRpc::XmlRpcValue(2), kParameter);
            }).rfind(prefix + "expected the namespaces", 0),
            0u);
  EXPECT_EQ(refusal([] {
              robotNamespaces(list({std::string("robot1"), 2}), kParameter);
            }).rfind(prefix + "element 2 of the list is not a name", 0),
            0u);
}

}  // namespace
}  // namespace rgbdmap
