// findmug/settings/settings.hpp — the one settings mechanism of every findmug program.
//
// A config file has sections (`forest:`, `table_map:`, `daemon:` ...) of
// `section.name` settings. Two pieces:
//
//  * SettingsTable<T>: the named settings of one struct T (key, how to parse
//    a value into T with the strict number parser findmug/common/numbers.hpp and a
//    range, how to print it back, what a value must be, a doc line, whether a model
//    records it), for one section or several (the segmenter's). Unknown keys and bad
//    values are findmug::Error naming the key. The core's tables live next to their
//    types (SegmenterConfig in segmenter_settings.cpp, OfflineConfig in
//    offline_settings.cpp, TableMapConfig in table_map.cpp, SemanticMapConfig in
//    semantic_map_settings.cpp);
//    the programs' own (daemon, check, web) in cli/program_settings.hpp.
//  * SettingsSchema: the tables a program states at start-up, each bound to the
//    struct its values go to (bind) or, for a section the program only has to
//    accept in a shared file, to defaults the schema owns (accept). The YAML
//    reader and the --set overrides hand each `section.name` to its table, which
//    parses it straight into the typed field: once, no text kept for later. A
//    section no table claims, or a key its table does not have, is an Error
//    naming it (and the file and line).
//
// This header is the bottom of the core: every room may include it (the aggregate of
// the core's settings, findmug/settings/config.hpp, is the top; tests/layering).
//
// A renamed key: its old name stays readable for one release through one alias
// table (renamedSettings, settings.cpp). The schema reads the old name as the
// new one with a warning naming the new key; a file (or the --set flags) that
// gives both names of one setting is refused naming both. Model files keep the
// names they were trained with, so their recorded keys go through
// currentSettingKey before they are compared.
#pragma once

#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"

namespace findmug {

// "invalid value 'V' for KEY (expected EXPECTED)".
[[noreturn]] void throwBadSettingValue(const std::string& key, const std::string& value,
                                       const std::string& expected);
// Numbers in messages (ranges): up to 9 significant digits, no exponent for 1e-4.
std::string formatSettingNumber(double value);
// A value as printed back (--check-config, the model file): the shortest text
// that reads back as the same float or double ("0.15", not "0.150000006").
std::string settingValueText(double value);
std::string settingValueText(float value);
bool parseSettingBool(const std::string& key, const std::string& value);

// One renamed setting, or a whole renamed section when both names end in ".*".
struct RenamedSetting {
  std::string old_key;  // "overseg.*", "forest.num_threads"
  std::string new_key;  // "oversegmentation.*", "learner.num_threads"
};
// Every renamed key of every findmug program, old -> new.
const std::vector<RenamedSetting>& renamedSettings();
// `key` under its current name: the new name of a renamed key, else `key` itself.
std::string currentSettingKey(const std::string& key);

template <typename T>
struct Setting {
  std::string key;       // "section.name"
  std::string doc;       // one line, printed by --help-settings (SettingsSchema::help)
  std::string expected;  // what a value must be ("a number in [0, 1]"), printed beside it
  // A model file records this setting's value at training (the feature-extraction
  // settings: what a feature means depends on them); loading the model makes it the
  // default (see configForModel, findmug/settings/config.hpp).
  bool recorded_in_model = false;
  std::function<void(T&, const std::string& value)> set;  // throws Error naming key
  std::function<std::string(const T&)> get;
};

// Where each setting a file or a flag gave explicitly came from, by its current key:
// "a.yaml: line 3", "--set". A struct with a member `given` of this type gets it
// filled by SettingsSchema::bind: SegmenterConfig, whose keys a model records take the
// model's value unless given explicitly.
using SettingOrigins = std::map<std::string, std::string>;

// One line of a settings listing (SettingsSchema::help, describe).
struct SettingHelp {
  std::string key, expected, value, doc;
  bool recorded_in_model = false;
};

template <typename T>
class SettingsTable {
 public:
  explicit SettingsTable(std::string section) : sections_{std::move(section)} {}
  // A table whose struct spans several sections (SegmenterConfig: cloud, forest, mrf ...).
  explicit SettingsTable(std::vector<std::string> sections) : sections_(std::move(sections)) {}

  // Refuses a second setting with the same key and a key outside the sections.
  SettingsTable& add(Setting<T> setting) {
    if (!holds(sectionOf(setting.key))) {
      throw Error("setting '" + setting.key + "' does not belong to section '" + sectionList() +
                  "'");
    }
    for (const auto& s : settings_) {
      if (s.key == setting.key) throw Error("setting '" + setting.key + "' registered twice");
    }
    settings_.push_back(std::move(setting));
    return *this;
  }

  const std::string& section() const { return sections_.front(); }
  const std::vector<std::string>& sections() const { return sections_; }
  bool holds(const std::string& section) const {
    return std::find(sections_.begin(), sections_.end(), section) != sections_.end();
  }
  const std::vector<Setting<T>>& settings() const { return settings_; }

  // Parses `value` into `target`. Unknown key: "unknown setting 'KEY' (SECTION keys: a, b)".
  void set(T& target, const std::string& key, const std::string& value) const {
    for (const auto& s : settings_) {
      if (s.key == key) {
        s.set(target, value);
        return;
      }
    }
    const std::string section = holds(sectionOf(key)) ? sectionOf(key) : this->section();
    throw Error("unknown setting '" + key + "' (" + section + " keys: " + keyList(section) + ")");
  }

  // Validates one key=value against defaults.
  void check(const std::string& key, const std::string& value) const {
    T scratch{};
    set(scratch, key, value);
  }

  // Every key of the table with its value in `target`, in key order.
  std::map<std::string, std::string> values(const T& target) const {
    std::map<std::string, std::string> out;
    for (const auto& s : settings_) out[s.key] = s.get(target);
    return out;
  }
  // The same in the table's own order (the order of the doc and the dump).
  std::vector<std::pair<std::string, std::string>> entries(const T& target) const {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& s : settings_) out.emplace_back(s.key, s.get(target));
    return out;
  }

  // The keys of one section (the first when not named), sorted, comma separated.
  std::string keyList(const std::string& section = {}) const {
    const std::string& wanted = section.empty() ? this->section() : section;
    std::vector<std::string> keys;
    for (const auto& s : settings_) {
      if (sectionOf(s.key) == wanted) keys.push_back(s.key);
    }
    std::sort(keys.begin(), keys.end());
    std::string out;
    for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
    return out;
  }

  static std::string sectionOf(const std::string& key) { return key.substr(0, key.find('.')); }

 private:
  std::string sectionList() const {
    std::string out;
    for (const auto& s : sections_) out += (out.empty() ? "" : "|") + s;
    return out;
  }

  std::vector<std::string> sections_;
  std::vector<Setting<T>> settings_;
};

// Builders. `field` returns a reference to the member in T. Ranges are inclusive.
template <typename T, typename Number>
Setting<T> numberSetting(std::string key, std::function<Number&(T&)> field, double lo, double hi,
                         std::string doc = {}) {
  Setting<T> s;
  s.key = key;
  s.doc = std::move(doc);
  s.expected = "a number in [" + formatSettingNumber(lo) + ", " + formatSettingNumber(hi) + "]";
  s.set = [key, field, lo, hi](T& t, const std::string& v) {
    const auto x = parseNumber(v);
    if (!x || *x < lo || *x > hi) {
      throwBadSettingValue(
          key, v, "a number in [" + formatSettingNumber(lo) + ", " + formatSettingNumber(hi) + "]");
    }
    field(t) = static_cast<Number>(*x);
  };
  s.get = [field](const T& t) { return settingValueText(field(const_cast<T&>(t))); };
  return s;
}

template <typename T, typename Integer>
Setting<T> integerSetting(std::string key, std::function<Integer&(T&)> field, long long lo,
                          long long hi, std::string doc = {}) {
  Setting<T> s;
  s.key = key;
  s.doc = std::move(doc);
  s.expected = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  s.set = [key, field, lo, hi](T& t, const std::string& v) {
    const auto x = parseInteger(v);
    if (!x || *x < lo || *x > hi) {
      throwBadSettingValue(
          key, v, "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    field(t) = static_cast<Integer>(*x);
  };
  s.get = [field](const T& t) { return std::to_string(field(const_cast<T&>(t))); };
  return s;
}

template <typename T>
Setting<T> boolSetting(std::string key, std::function<bool&(T&)> field, std::string doc = {}) {
  Setting<T> s;
  s.key = key;
  s.doc = std::move(doc);
  s.expected = "true or false";
  s.set = [key, field](T& t, const std::string& v) { field(t) = parseSettingBool(key, v); };
  s.get = [field](const T& t) { return std::string(field(const_cast<T&>(t)) ? "true" : "false"); };
  return s;
}

template <typename T, typename Enum>
Setting<T> enumSetting(std::string key, std::function<Enum&(T&)> field,
                       std::vector<std::pair<std::string, Enum>> names, std::string doc = {}) {
  Setting<T> s;
  s.key = key;
  s.doc = std::move(doc);
  s.expected = "one of";
  for (const auto& n : names) s.expected += " " + n.first;
  s.set = [key, field, names](T& t, const std::string& v) {
    for (const auto& [name, value] : names) {
      if (name == v) {
        field(t) = value;
        return;
      }
    }
    std::string expected = "one of";
    for (const auto& n : names) expected += " " + n.first;
    throwBadSettingValue(key, v, expected);
  };
  s.get = [field, names](const T& t) {
    const Enum e = field(const_cast<T&>(t));
    for (const auto& [name, value] : names) {
      if (value == e) return name;
    }
    return std::string("?");
  };
  return s;
}

// `check` returns "" when the value is fine, else what was expected.
template <typename T>
Setting<T> textSetting(std::string key, std::function<std::string&(T&)> field,
                       std::function<std::string(const std::string&)> check, std::string doc = {}) {
  Setting<T> s;
  s.key = key;
  s.doc = std::move(doc);
  s.expected = "text";
  s.set = [key, field, check](T& t, const std::string& v) {
    if (check) {
      const std::string expected = check(v);
      if (!expected.empty()) throwBadSettingValue(key, v, expected);
    }
    field(t) = v;
  };
  s.get = [field](const T& t) { return field(const_cast<T&>(t)); };
  return s;
}

// The settings a program reads, stated at start-up: every table it knows, bound
// to where its values go. Reading is: readFile/readYaml, then applyOverride for
// each --set, then validate (the cross-key rules) once.
class SettingsSchema {
 public:
  // Binds every section of `table` to `target`, which must outlive the schema.
  // `validate` (optional) checks the struct as a whole after reading and throws
  // findmug::Error naming the keys. A section bound twice is refused.
  template <typename T>
  SettingsSchema& bind(const SettingsTable<T>& table, T& target,
                       std::type_identity_t<std::function<void(const T&)>> validate = {}) {
    auto shared = std::make_shared<const SettingsTable<T>>(table);
    Binding b;
    b.sections = table.sections();
    b.set = [shared, &target](const std::string& key, const std::string& value) {
      shared->set(target, key, value);
    };
    if constexpr (requires { target.given; }) {
      b.record = [&target](const std::string& key, const std::string& place) {
        target.given[key] = place;
      };
    }
    b.entries = [shared, &target] { return shared->entries(target); };
    b.describe = [shared, &target] { return describeSettings(*shared, target); };
    if (validate) b.validate = [validate, &target] { validate(target); };
    add(std::move(b));
    return *this;
  }
  // A section of another program sharing the file: accepted, every key checked
  // and parsed into defaults the schema owns (a typo is refused here too), unused.
  template <typename T>
  SettingsSchema& accept(const SettingsTable<T>& table,
                         std::type_identity_t<std::function<void(const T&)>> validate = {}) {
    auto owned = std::make_shared<T>();
    auto shared = std::make_shared<const SettingsTable<T>>(table);
    Binding b;
    b.sections = table.sections();
    b.set = [shared, owned](const std::string& key, const std::string& value) {
      shared->set(*owned, key, value);
    };
    b.entries = [shared, owned] { return shared->entries(*owned); };
    b.describe = [shared, owned] { return describeSettings(*shared, *owned); };
    if (validate) b.validate = [validate, owned] { validate(*owned); };
    b.accepted_only = true;
    add(std::move(b));
    return *this;
  }

  bool has(const std::string& section) const;
  // "section.name" = value into its field. Throws Error naming the key. A
  // renamed key's old name sets the new one, with a warning; a file (or the
  // flags, or the calls of set) giving both names of one setting is refused.
  void set(const std::string& key, const std::string& value) const { setFrom(key, value, "", ""); }
  // Where warnings go (an old key name read); default: a line on stderr.
  void onWarning(std::function<void(const std::string&)> sink) { warn_ = std::move(sink); }
  // A YAML file's text: a map of sections, each a map of single values, every
  // one handed to its table. `origin` (a path) and the line name an error.
  void readYaml(const std::string& text, const std::string& origin) const;
  void readFile(const std::string& path) const;
  // "section.name=value" (a --set flag); errors say "<flags>".
  void applyOverride(const std::string& key_equals_value) const;
  // The cross-key rules of every table; `origin` names where the values came from.
  void validate(const std::string& origin) const;
  // The effective values of the bound sections (not the accepted ones) as YAML,
  // sections in name order, keys in table order (--check-config, the start-up log).
  std::string dump() const;
  // Every setting of every table the schema knows, bound or accepted, sections in
  // name order, keys in table order, with its current value.
  std::vector<SettingHelp> describe() const;
  // describe() as text (--help-settings): per setting, "key = value  (expected)" and
  // its doc line indented below; "[model]" marks the keys a model records.
  std::string help() const;

 private:
  template <typename T>
  static std::vector<SettingHelp> describeSettings(const SettingsTable<T>& table, const T& values) {
    std::vector<SettingHelp> out;
    for (const auto& s : table.settings()) {
      out.push_back({s.key, s.expected, s.get(values), s.doc, s.recorded_in_model});
    }
    return out;
  }
  struct Binding {
    std::vector<std::string> sections;
    std::function<void(const std::string&, const std::string&)> set;
    // Notes where a key was given (structs with a `given` member, SettingOrigins).
    std::function<void(const std::string& key, const std::string& place)> record;
    std::function<std::vector<SettingHelp>()> describe;
    std::function<std::vector<std::pair<std::string, std::string>>()> entries;
    std::function<void()> validate;
    bool accepted_only = false;
  };
  void add(Binding binding);
  // set() for a key read from `origin` (a path, "<flags>"); `where` starts its
  // messages ("a.yaml: line 3: ").
  void setFrom(const std::string& key, const std::string& value, const std::string& origin,
               const std::string& where) const;
  const Binding* find(const std::string& section) const;

  std::vector<Binding> bindings_;
  std::function<void(const std::string&)> warn_;
  // Of every setting read, by its current key: the name it was given as, the
  // origin and the place, to refuse one origin naming a setting by both names.
  struct Given {
    std::string key, origin, where;
  };
  mutable std::map<std::string, Given> given_;
};

}  // namespace findmug
