// findmug/settings/settings.hpp — the one settings mechanism of every findmug program.
//
// A config file has sections (`forest:`, `table_map:`, `daemon:` ...) of
// `section.name` settings. Two pieces:
//
//  * SettingsTable<T>: the named settings of one struct T (key, how to parse
//    a value into T with the strict number parser findmug/common/numbers.hpp and a
//    range, how to print it back, a doc line). Unknown keys and bad values are
//    findmug::Error naming the key. The core's own tables live next to their
//    types (SegmenterConfig in config.cpp, TableMapConfig in table_map.cpp);
//    the daemon keeps its own in daemon/.
//  * ConfigSections (configSections()): the sections a program accepts that
//    are not part of SegmenterConfig, each registered by its owner. With a
//    check (normally SettingsTable::check), parseConfig validates every key
//    as it reads it; known by name only (addSectionName), the section belongs
//    to another program reading the same file and its keys are kept unchecked.
//    Either way the raw values land in Config::extra for the owner to resolve.
//    The core registers `table_map`; the daemon registers `daemon` and
//    `check`; the cli layer declares the names of the project's other
//    sections (cli::declareProjectSections), so findmug-train/-eval accept
//    the daemon's file without knowing its keys. A section not registered at
//    all is an "unknown setting" error.
//
// Registration happens at start-up, before any config is read (no locking).
#pragma once

#include <algorithm>
#include <functional>
#include <map>
#include <string>
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
// A value as printed back (--check-config, Config::extra): the shortest text
// that reads back as the same float or double ("0.15", not "0.150000006").
std::string settingValueText(double value);
std::string settingValueText(float value);
bool parseSettingBool(const std::string& key, const std::string& value);

template <typename T>
struct Setting {
  std::string key;                                        // "section.name"
  std::string doc;                                        // one line for --help style listings
  std::function<void(T&, const std::string& value)> set;  // throws Error naming key
  std::function<std::string(const T&)> get;
};

template <typename T>
class SettingsTable {
 public:
  explicit SettingsTable(std::string section) : section_(std::move(section)) {}

  // Refuses a second setting with the same key and a key outside the section.
  SettingsTable& add(Setting<T> setting) {
    if (setting.key.rfind(section_ + ".", 0) != 0) {
      throw Error("setting '" + setting.key + "' does not belong to section '" + section_ + "'");
    }
    for (const auto& s : settings_) {
      if (s.key == setting.key) throw Error("setting '" + setting.key + "' registered twice");
    }
    settings_.push_back(std::move(setting));
    return *this;
  }

  const std::string& section() const { return section_; }
  const std::vector<Setting<T>>& settings() const { return settings_; }

  // Parses `value` into `target`. Unknown key: "unknown setting 'KEY' (SECTION keys: a, b)".
  void set(T& target, const std::string& key, const std::string& value) const {
    for (const auto& s : settings_) {
      if (s.key == key) {
        s.set(target, value);
        return;
      }
    }
    throw Error("unknown setting '" + key + "' (" + section_ + " keys: " + keyList() + ")");
  }

  // Validates one key=value against defaults (for ConfigSections).
  void check(const std::string& key, const std::string& value) const {
    T scratch{};
    set(scratch, key, value);
  }

  // Every key of the section with its value in `target`, in key order.
  std::map<std::string, std::string> values(const T& target) const {
    std::map<std::string, std::string> out;
    for (const auto& s : settings_) out[s.key] = s.get(target);
    return out;
  }

  std::string keyList() const {
    std::vector<std::string> keys;
    for (const auto& s : settings_) keys.push_back(s.key);
    std::sort(keys.begin(), keys.end());
    std::string out;
    for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
    return out;
  }

 private:
  std::string section_;
  std::vector<Setting<T>> settings_;
};

// Builders. `field` returns a reference to the member in T. Ranges are inclusive.
template <typename T, typename Number>
Setting<T> numberSetting(std::string key, std::function<Number&(T&)> field, double lo, double hi,
                         std::string doc = {}) {
  Setting<T> s;
  s.key = key;
  s.doc = std::move(doc);
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

class ConfigSections {
 public:
  // Validates one "section.name" = value; throws findmug::Error naming the key.
  using Check = std::function<void(const std::string& key, const std::string& value)>;

  // A section whose keys `check` validates. A section registered with a check
  // before is refused (two owners); one known by name only gains the check.
  void addSection(const std::string& name, Check check);
  // A section of another program: accepted, keys unchecked. Idempotent.
  void addSectionName(const std::string& name);

  bool has(const std::string& name) const { return sections_.count(name) != 0; }
  // Checks key=value when the section has a check. Throws for an unregistered section.
  void check(const std::string& section, const std::string& key, const std::string& value) const;

 private:
  std::map<std::string, Check> sections_;  // empty Check: known by name only
};

// The process-wide registry parseConfig consults; holds `table_map` from the start.
ConfigSections& configSections();

}  // namespace findmug
