#pragma once

#include <functional>
#include <string>
#include <vector>

namespace rgbdmap {

// One config key ("section.name") bound to a field of an option struct. Each layer lists the
// keys of its own option structs (e.g. mappingKeys in mapping/); the run's configuration
// (runtime/config.hpp) joins them into one table that YAML files, `--set` and ROS parameters
// fill. The default is the field's initial value: there is no other copy of it.
struct Key {
  std::string name;
  std::string help;
  std::function<void(const std::string&)> set;  // throws std::invalid_argument with why
  std::function<std::string()> get;
  // A former name of key `replaced_by`: still read (a configuration saved before the rename
  // loads, with a deprecation warning), never listed or written.
  std::string replaced_by;
};
using Keys = std::vector<Key>;

// Keys of each kind, parsing text and checking ranges (inclusive).
// The whole of `text` as a finite number (false for "", "1x", "nan", "inf").
bool parseFiniteNumber(const std::string& text, double& value);
Key number(const std::string& name, double* field, double lo, double hi, const std::string& help);
Key integer(const std::string& name, int* field, int lo, int hi, const std::string& help);
Key boolean(const std::string& name, bool* field, const std::string& help);
Key choice(const std::string& name, std::string* field, std::vector<std::string> options,
           const std::string& help);
Key text(const std::string& name, std::string* field, const std::string& help);
// `key`, whose setter afterwards runs `check` (which throws std::invalid_argument with why): for
// limits that join two keys, such as a range's ends.
Key checked(Key key, std::function<void()> check);

// `now` under a former name `old_name` (see Key::replaced_by).
Key formerName(const std::string& old_name, const Key& now);

// Appends `more` to `keys`.
void append(Keys& keys, Keys more);

// Sets one key from text; throws InputError naming the key (and `origin`) when the key is unknown
// or the value is invalid or out of range. A former name sets its key and warns, naming `origin`
// and the key's name now.
void setKey(Keys& keys, const std::string& key, const std::string& value,
            const std::string& origin);
// Applies a YAML file (nested maps, e.g. `map: {voxel_size: 0.01}`); a top-level `preset` entry
// goes to `preset`. Throws InputError naming the file and line. Former names (a configuration
// saved by an older version) are read, with one warning line for the file naming the keys now.
void loadYamlKeys(Keys& keys, const std::string& path, std::string& preset);
// The YAML file of a preset name ("tum_fr1", in the config folder) or the path itself when it
// names a file; throws InputError for an unknown name.
std::string presetPath(const std::string& name_or_path);
std::string presetDirectory();
// Every key with its value and help as YAML, one section per map.
std::string keysToYaml(const Keys& keys, const std::string& preset);
// Every key with its value and help: one per line, or the Markdown table of
// docs/configuration.md (a test compares them).
std::string listKeys(const Keys& keys, bool markdown);

}  // namespace rgbdmap
