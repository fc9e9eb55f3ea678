#include <cstdio>

#include "rgbdmap/base/text_lines.hpp"
#include "rgbdmap/capture/association.hpp"
#include "rgbdmap/tools/commands.hpp"

namespace rgbdmap {
namespace {

struct Rows {
  std::vector<double> stamps;
  std::vector<std::string> rest;  // the fields after the timestamp, joined by spaces
};

Rows readRows(const std::string& path) {
  Rows rows;
  for (const TextLine& line : readTextLines(path)) {
    rows.stamps.push_back(parseNumber(line.fields[0], path, line.number, "timestamp"));
    std::string rest;
    for (std::size_t i = 1; i < line.fields.size(); ++i) rest += " " + line.fields[i];
    rows.rest.push_back(rest);
  }
  return rows;
}

}  // namespace

void addAssociateCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "associate", "match two TUM lists by timestamp (TUM's associate.py rule), print the pairs");
  struct Options {
    std::string first, second;
    double max_difference = 0.02, offset = 0.0;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("first", o->first, "first list (e.g. rgb.txt)")->required();
  cmd->add_option("second", o->second, "second list (e.g. depth.txt)")->required();
  cmd->add_option("--max-difference", o->max_difference, "seconds")->capture_default_str();
  cmd->add_option("--offset", o->offset, "seconds added to the second list's stamps")
      ->capture_default_str();
  cmd->callback([o, &selected] {
    selected = [o] {
      const Rows a = readRows(o->first), b = readRows(o->second);
      for (const auto& [i, j] : associate(a.stamps, b.stamps, o->max_difference, o->offset))
        std::printf("%.6f%s %.6f%s\n", a.stamps[i], a.rest[i].c_str(), b.stamps[j],
                    b.rest[j].c_str());
      return 0;
    };
  });
}

}  // namespace rgbdmap
