#include "rgbdmap/ros/robot_namespaces.hpp"

#include <cctype>
#include <set>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {
namespace {

const char* const kSpellings =
    "the namespaces of two robots or more, the first one's frame is the merged map's: "
    "_robots:=\"[robot1, robot2]\", _robots:=\"robot1 robot2\" or a rosparam list";

bool separator(char c) { return c == ',' || std::isspace(static_cast<unsigned char>(c)); }

// The names in one string: a YAML flow list ("[a, 'b']") or words separated by spaces or commas.
std::vector<std::string> namesIn(const std::string& text, const std::string& parameter) {
  std::size_t begin = 0, end = text.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(text[begin]))) ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
  if (begin < end && text[begin] == '[') {
    if (text[end - 1] != ']')
      throw InputError("parameter " + parameter + ": the list \"" + text +
                       "\" is not closed by ']'");
    ++begin, --end;
  }
  std::vector<std::string> names;
  for (std::size_t i = begin; i < end;) {
    if (separator(text[i])) {
      ++i;
    } else if (text[i] == '\'' || text[i] == '"') {
      const std::size_t close = text.find(text[i], i + 1);
      if (close == std::string::npos || close >= end)
        throw InputError("parameter " + parameter + ": a quote in \"" + text + "\" is not closed");
      names.push_back(text.substr(i + 1, close - i - 1));
      i = close + 1;
    } else {
      std::size_t word_end = i;
      while (word_end < end && !separator(text[word_end])) ++word_end;
      names.push_back(text.substr(i, word_end - i));
      i = word_end;
    }
  }
  return names;
}

// A ROS graph resource name: segments separated by '/', each a letter followed by letters,
// digits and '_'.
bool validName(const std::string& absolute) {
  std::size_t segment_start = 1;
  for (std::size_t i = 1; i <= absolute.size(); ++i) {
    if (i == absolute.size() || absolute[i] == '/') {
      if (i == segment_start) return false;  // an empty segment ("a//b")
      segment_start = i + 1;
      continue;
    }
    const auto c = static_cast<unsigned char>(absolute[i]);
    if (i == segment_start ? !std::isalpha(c) : !(std::isalnum(c) || c == '_')) return false;
  }
  return true;
}

}  // namespace

std::vector<std::string> robotNamespaces(const XmlRpc::XmlRpcValue& value,
                                         const std::string& parameter) {
  std::vector<std::string> given;
  switch (value.getType()) {
    case XmlRpc::XmlRpcValue::TypeInvalid:  // not set
      break;
    case XmlRpc::XmlRpcValue::TypeString:
      given = namesIn(static_cast<const std::string&>(value), parameter);
      break;
    case XmlRpc::XmlRpcValue::TypeArray:
      for (int i = 0; i < value.size(); ++i) {
        if (value[i].getType() != XmlRpc::XmlRpcValue::TypeString)
          throw InputError("parameter " + parameter + ": element " + std::to_string(i + 1) +
                           " of the list is not a name; " + kSpellings);
        given.push_back(static_cast<const std::string&>(value[i]));
      }
      break;
    default:
      throw InputError("parameter " + parameter + ": expected " + kSpellings);
  }
  std::vector<std::string> robots;
  std::set<std::string> seen;
  for (const std::string& name : given) {
    std::string r = name;
    while (!r.empty() && r.back() == '/') r.pop_back();
    if (r.empty() || r.front() != '/') r = "/" + r;
    if (r == "/" || !validName(r))
      throw InputError("parameter " + parameter + ": '" + name +
                       "' is not a namespace (a ROS name: letters, digits, '_' and '/', each part "
                       "starting with a letter)");
    if (!seen.insert(r).second)
      throw InputError("parameter " + parameter + ": " + r + " is listed twice");
    robots.push_back(r);
  }
  if (robots.size() < 2) throw InputError("parameter " + parameter + ": " + kSpellings);
  return robots;
}

}  // namespace rgbdmap
