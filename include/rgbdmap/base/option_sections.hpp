#pragma once

#include <any>
#include <functional>
#include <map>
#include <string>
#include <typeindex>
#include <vector>

#include "rgbdmap/base/option_keys.hpp"

namespace rgbdmap {

// Option sections that an adapter outside the core adds to the run's configuration (the ROS
// adapter's ros.* topics): the core neither knows their types nor their keys. An adapter registers
// its option struct with its key table once (a static initializer); every configuration then
// holds one value of it, reached by type.
class OptionSections {
 public:
  // Registers T (default-constructed in every configuration) with the keys of one value. Its
  // keys follow those of section `after` in the key table. Returns true, for static initializers.
  template <class T>
  static bool add(const std::string& after, Keys (*keys)(T&)) {
    addSection({std::type_index(typeid(T)), after, [] { return std::any(T{}); },
                [keys](std::any& value) { return keys(std::any_cast<T&>(value)); }});
    return true;
  }

  // This configuration's value of T (defaults until a key sets it).
  template <class T>
  T& get() {
    return std::any_cast<T&>(value(std::type_index(typeid(T)), [] { return std::any(T{}); }));
  }
  template <class T>
  const T& get() const {
    const auto found = values_.find(std::type_index(typeid(T)));
    if (found != values_.end()) return std::any_cast<const T&>(found->second);
    static const T defaults{};
    return defaults;
  }

  // `keys` with the keys of every registered section inserted after their `after` section.
  Keys insertInto(Keys keys);

 private:
  struct Section {
    std::type_index type;
    std::string after;
    std::function<std::any()> make;
    std::function<Keys(std::any&)> keys;
  };
  static void addSection(Section section);
  static std::vector<Section>& registry();
  std::any& value(std::type_index type, const std::function<std::any()>& make);

  std::map<std::type_index, std::any> values_;
};

}  // namespace rgbdmap
