#include "rgbdmap/base/option_sections.hpp"

#include <utility>

namespace rgbdmap {

std::vector<OptionSections::Section>& OptionSections::registry() {
  static std::vector<Section> sections;
  return sections;
}

void OptionSections::addSection(Section section) {
  for (const Section& s : registry())
    if (s.type == section.type) return;
  registry().push_back(std::move(section));
}

std::any& OptionSections::value(std::type_index type, const std::function<std::any()>& make) {
  auto found = values_.find(type);
  if (found == values_.end()) found = values_.emplace(type, make()).first;
  return found->second;
}

Keys OptionSections::insertInto(Keys keys) {
  for (const Section& s : registry()) {
    Keys more = s.keys(value(s.type, s.make));
    // After the last key of section `after` (at the end when there is none).
    auto at = keys.end();
    for (auto k = keys.begin(); k != keys.end(); ++k)
      if (k->name.rfind(s.after + ".", 0) == 0) at = k + 1;
    keys.insert(at, std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()));
  }
  return keys;
}

}  // namespace rgbdmap
