#include "rgbdmap/base/option_keys.hpp"

#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {
namespace {

std::string formatNumber(double v) {
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

// Flattens nested YAML maps into "a.b" keys with scalar values.
void flatten(const YAML::Node& node, const std::string& prefix,
             std::vector<std::pair<std::string, YAML::Node>>& out) {
  if (node.IsMap()) {
    for (const auto& item : node)
      flatten(item.second,
              prefix.empty() ? item.first.as<std::string>()
                             : prefix + "." + item.first.as<std::string>(),
              out);
  } else {
    out.emplace_back(prefix, node);
  }
}

}  // namespace

bool parseFiniteNumber(const std::string& text, double& value) {
  std::size_t used = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used > 0 && used == text.size() && std::isfinite(value);
}

Key number(const std::string& name, double* field, double lo, double hi, const std::string& help) {
  return {name, help,
          [=](const std::string& text) {
            double v = 0;
            if (!parseFiniteNumber(text, v))
              throw std::invalid_argument("'" + text + "' is not a number");
            if (v < lo || v > hi)
              throw std::invalid_argument(text + " is outside [" + formatNumber(lo) + ", " +
                                          formatNumber(hi) + "]");
            *field = v;
          },
          [=] { return formatNumber(*field); }, ""};
}

Key integer(const std::string& name, int* field, int lo, int hi, const std::string& help) {
  return {name, help,
          [=](const std::string& text) {
            std::size_t used = 0;
            long v = 0;
            try {
              v = std::stol(text, &used);
            } catch (const std::exception&) {
              used = 0;
            }
            if (used == 0 || used != text.size())
              throw std::invalid_argument("'" + text + "' is not an integer");
            if (v < lo || v > hi)
              throw std::invalid_argument(text + " is outside [" + std::to_string(lo) + ", " +
                                          std::to_string(hi) + "]");
            *field = static_cast<int>(v);
          },
          [=] { return std::to_string(*field); }, ""};
}

Key boolean(const std::string& name, bool* field, const std::string& help) {
  return {name, help,
          [=](const std::string& text) {
            if (text == "true" || text == "1" || text == "yes" || text == "on")
              *field = true;
            else if (text == "false" || text == "0" || text == "no" || text == "off")
              *field = false;
            else
              throw std::invalid_argument("'" + text + "' is not true or false");
          },
          [=] { return std::string(*field ? "true" : "false"); }, ""};
}

Key choice(const std::string& name, std::string* field, std::vector<std::string> options,
           const std::string& help) {
  return {name, help,
          [=](const std::string& text) {
            for (const std::string& o : options)
              if (o == text) {
                *field = text;
                return;
              }
            std::string list;
            for (const std::string& o : options) list += (list.empty() ? "" : ", ") + o;
            throw std::invalid_argument("'" + text + "' is not one of " + list);
          },
          [=] { return *field; }, ""};
}

Key text(const std::string& name, std::string* field, const std::string& help) {
  return {name, help, [=](const std::string& value) { *field = value; }, [=] { return *field; },
          ""};
}

Key checked(Key key, std::function<void()> check) {
  key.set = [set = std::move(key.set), check = std::move(check)](const std::string& value) {
    set(value);
    check();
  };
  return key;
}

Key formerName(const std::string& old_name, const Key& now) {
  Key former = now;
  former.name = old_name;
  former.help = "former name of " + now.name;
  former.replaced_by = now.name;
  return former;
}

void append(Keys& keys, Keys more) {
  for (Key& k : more) keys.push_back(std::move(k));
}

namespace {

// Sets one key (see setKey) and returns it.
const Key& setOne(Keys& keys, const std::string& key, const std::string& value,
                  const std::string& origin) {
  for (Key& k : keys) {
    if (k.name != key) continue;
    try {
      k.set(value);
    } catch (const std::invalid_argument& e) {
      throw InputError(origin + ": " + key + ": " + e.what());
    }
    return k;
  }
  throw InputError(origin + ": unknown config key '" + key + "' (see `rgbdmap --list-keys`)");
}

// "tracking.undistort and filter.undistort are now camera.undistort": the former names read, by
// the key each is now.
std::string formerNamesNow(const std::vector<const Key*>& read) {
  std::vector<std::pair<std::string, std::vector<std::string>>> by_key;
  for (const Key* k : read) {
    auto at = std::find_if(by_key.begin(), by_key.end(),
                           [k](const auto& entry) { return entry.first == k->replaced_by; });
    if (at == by_key.end()) at = by_key.insert(by_key.end(), {k->replaced_by, {}});
    if (std::find(at->second.begin(), at->second.end(), k->name) == at->second.end())
      at->second.push_back(k->name);
  }
  std::string text;
  for (const auto& [now, names] : by_key) {
    std::string former;
    for (std::size_t i = 0; i < names.size(); ++i)
      former += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
    text +=
        (text.empty() ? "" : "; ") + former + (names.size() > 1 ? " are" : " is") + " now " + now;
  }
  return text;
}

}  // namespace

void setKey(Keys& keys, const std::string& key, const std::string& value,
            const std::string& origin) {
  const Key& set = setOne(keys, key, value, origin);
  if (!set.replaced_by.empty())
    spdlog::warn("{}: {} (a former name, still read)", origin, formerNamesNow({&set}));
}

void loadYamlKeys(Keys& keys, const std::string& path, std::string& preset) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path + ": cannot open config file");
  } catch (const YAML::Exception& e) {
    throw InputError(path + ":" + std::to_string(e.mark.line + 1) + ": invalid YAML: " + e.msg);
  }
  if (root.IsNull()) return;
  if (!root.IsMap()) throw InputError(path + ": expected a map of config sections");
  std::vector<std::pair<std::string, YAML::Node>> items;
  flatten(root, "", items);
  std::vector<const Key*> former;  // former names read
  for (const auto& [key, node] : items) {
    const std::string origin = path + ":" + std::to_string(node.Mark().line + 1);
    if (key == "preset") {
      preset = node.as<std::string>();
      continue;
    }
    if (!node.IsScalar()) throw InputError(origin + ": " + key + ": expected a single value");
    const Key& set = setOne(keys, key, node.as<std::string>(), origin);
    if (!set.replaced_by.empty()) former.push_back(&set);
  }
  if (!former.empty())
    spdlog::warn("{}: {} (former names, still read)", path, formerNamesNow(former));
}

std::string presetDirectory() { return RGBDMAP_CONFIG_DIR; }

std::string presetPath(const std::string& name_or_path) {
  const bool is_path = name_or_path.find('/') != std::string::npos ||
                       name_or_path.find(".yaml") != std::string::npos;
  if (is_path) return name_or_path;
  const std::string path = presetDirectory() + "/" + name_or_path + ".yaml";
  if (!std::ifstream(path))
    throw InputError("unknown preset '" + name_or_path + "' (no " + path + ")");
  return path;
}

std::string keysToYaml(const Keys& keys, const std::string& preset) {
  std::ostringstream out;
  out << "# rgbdmap effective configuration";
  if (!preset.empty()) out << " (preset " << preset << ")";
  out << "\n";
  std::string section;
  for (const Key& k : keys) {
    if (!k.replaced_by.empty()) continue;
    const std::string s = k.name.substr(0, k.name.find('.'));
    if (s != section) {
      section = s;
      out << section << ":\n";
    }
    std::string value = k.get();
    if (value.empty()) value = "\"\"";
    out << "  " << k.name.substr(k.name.find('.') + 1) << ": " << value << "  # " << k.help << "\n";
  }
  return out.str();
}

std::string listKeys(const Keys& keys, bool markdown) {
  std::string list;
  if (!markdown) {
    // Columns as printf's "%-28s %-12s %s".
    auto pad = [](std::string text, std::size_t width) {
      if (text.size() < width) text.append(width - text.size(), ' ');
      return text;
    };
    for (const Key& k : keys)
      if (k.replaced_by.empty())
        list += pad(k.name, 28) + " " + pad(k.get(), 12) + " " + k.help + "\n";
    return list;
  }
  auto escape = [](std::string text) {
    for (std::size_t at = text.find('|'); at != std::string::npos; at = text.find('|', at + 2))
      text.replace(at, 1, "\\|");
    return text;
  };
  list = "| key | default | meaning |\n| --- | --- | --- |\n";
  for (const Key& k : keys) {
    if (!k.replaced_by.empty()) continue;
    const std::string value = k.get();
    list += "| `" + k.name + "` | " + (value.empty() ? "" : "`" + escape(value) + "`") + " | " +
            escape(k.help) + " |\n";
  }
  return list;
}

}  // namespace rgbdmap
