// settings.cpp — the settings mechanism shared by every layer (see settings.hpp).
#include "findmug/settings/settings.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <iostream>
#include <sstream>

namespace findmug {

void throwBadSettingValue(const std::string& key, const std::string& value,
                          const std::string& expected) {
  throw Error("invalid value '" + value + "' for " + key + " (expected " + expected + ")");
}

std::string formatSettingNumber(double value) {
  std::ostringstream s;
  s.precision(9);
  s << value;
  return s.str();
}

namespace {
template <typename Number>
std::string shortestText(Number value) {
  char text[64];
  const auto end = std::to_chars(text, text + sizeof text, value);
  return std::string(text, end.ptr);
}
}  // namespace

std::string settingValueText(double value) { return shortestText(value); }
std::string settingValueText(float value) { return shortestText(value); }

bool parseSettingBool(const std::string& key, const std::string& value) {
  if (value == "true" || value == "yes" || value == "on" || value == "1") return true;
  if (value == "false" || value == "no" || value == "off" || value == "0") return false;
  throwBadSettingValue(key, value, "true or false");
}

const std::vector<RenamedSetting>& renamedSettings() {
  // Kept for one release after the rename, then removed (the old name is then unknown).
  static const std::vector<RenamedSetting> all = {
      // The step is called oversegmentation everywhere (its room, status_t's stage name).
      {"overseg.*", "oversegmentation.*"},
      // What trains either learner (the forest and the boosted trees) is learner.*.
      {"forest.class_weighting", "learner.class_weighting"},
      {"forest.num_threads", "learner.num_threads"},
  };
  return all;
}

std::string currentSettingKey(const std::string& key) {
  for (const auto& r : renamedSettings()) {
    const bool section =
        r.old_key.size() > 2 && r.old_key.compare(r.old_key.size() - 2, 2, ".*") == 0;
    if (!section) {
      if (key == r.old_key) return r.new_key;
      continue;
    }
    const std::string old_prefix = r.old_key.substr(0, r.old_key.size() - 1);  // "overseg."
    if (key.size() > old_prefix.size() && key.compare(0, old_prefix.size(), old_prefix) == 0) {
      return r.new_key.substr(0, r.new_key.size() - 1) + key.substr(old_prefix.size());
    }
  }
  return key;
}

void SettingsSchema::add(Binding binding) {
  for (const auto& section : binding.sections) {
    if (has(section)) throw Error("settings section '" + section + "' bound twice");
  }
  bindings_.push_back(std::move(binding));
}

const SettingsSchema::Binding* SettingsSchema::find(const std::string& section) const {
  for (const auto& b : bindings_) {
    if (std::find(b.sections.begin(), b.sections.end(), section) != b.sections.end()) return &b;
  }
  return nullptr;
}

bool SettingsSchema::has(const std::string& section) const { return find(section) != nullptr; }

void SettingsSchema::setFrom(const std::string& given_key, const std::string& value,
                             const std::string& origin, const std::string& where) const {
  const auto given_dot = given_key.find('.');
  if (given_dot == std::string::npos || given_dot == 0 || given_dot + 1 == given_key.size()) {
    throw Error("setting '" + given_key + "' must be of the form section.name");
  }
  const std::string key = currentSettingKey(given_key);
  const auto [earlier, first] = given_.try_emplace(key, Given{given_key, origin, where});
  if (!first) {
    if (earlier->second.origin == origin && earlier->second.key != given_key) {
      const std::string old_key = key == given_key ? earlier->second.key : given_key;
      std::string place = earlier->second.where;  // "a.yaml: line 2: " -> " (a.yaml: line 2)"
      while (!place.empty() && (place.back() == ' ' || place.back() == ':')) place.pop_back();
      throw Error("setting '" + key + "' is given by both its names, '" + earlier->second.key +
                  "'" + (place.empty() ? "" : " (" + place + ")") + " and '" + given_key + "'; '" +
                  old_key + "' is its old name: keep only '" + key + "'");
    }
    earlier->second = Given{given_key, origin, where};
  }
  if (key != given_key) {
    const std::string warning = where + "setting '" + given_key + "' is now called '" + key +
                                "'; the old name is read for this release only";
    if (warn_) {
      warn_(warning);
    } else {
      std::cerr << "warning: " << warning << "\n";
    }
  }
  const auto dot = key.find('.');
  const Binding* binding = find(key.substr(0, dot));
  if (!binding) {
    std::vector<std::string> names;
    for (const auto& b : bindings_) names.insert(names.end(), b.sections.begin(), b.sections.end());
    std::sort(names.begin(), names.end());
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    throw Error("unknown setting '" + key + "': no section '" + key.substr(0, dot) +
                "' (sections: " + list + ")");
  }
  binding->set(key, value);
  if (binding->record) {
    // "a.yaml: line 3: " -> "a.yaml: line 3"; the flags -> "--set".
    std::string place = origin == "<flags>" ? std::string("--set") : where;
    while (!place.empty() && (place.back() == ' ' || place.back() == ':')) place.pop_back();
    binding->record(key, place.empty() ? std::string("the program") : place);
  }
}

namespace {

std::string lineOf(const YAML::Node& node) { return std::to_string(node.Mark().line + 1); }

// A map key as text. YAML allows maps and sequences as keys ("? [a, b]: 1"),
// which yaml-cpp's as<std::string>() answers with its own exception: name the
// place instead (found by fuzzing, tests/fuzz/regressions/config_yaml).
std::string keyText(const YAML::Node& key, const std::string& origin, const std::string& where) {
  if (!key.IsScalar()) {
    throw Error(origin + ": line " + lineOf(key) + ": " + where +
                " key must be a plain name, not a map or list");
  }
  return key.Scalar();
}

}  // namespace

void SettingsSchema::readYaml(const std::string& text, const std::string& origin) const {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(origin + ": not valid YAML: " + e.what());
  }
  if (root.IsNull()) return;  // an empty file means all defaults
  if (!root.IsMap()) throw Error(origin + ": top level must be a map of sections");
  for (const auto& section : root) {
    const std::string section_name = keyText(section.first, origin, "section");
    if (section.second.IsNull()) {
      // Every key commented out (daemon/findmugd.yaml's normals:, taken from the model):
      // nothing set, but the section must still be one the program knows.
      const std::string current = currentSettingKey(section_name + ".x");
      if (!has(current.substr(0, current.find('.')))) {
        throw Error(origin + ": line " + lineOf(section.first) + ": unknown section '" +
                    section_name + "'");
      }
      continue;
    }
    if (!section.second.IsMap()) {
      throw Error(origin + ": line " + lineOf(section.first) + ": section '" + section_name +
                  "' must be a map of settings");
    }
    for (const auto& entry : section.second) {
      const std::string key =
          section_name + "." + keyText(entry.first, origin, "section '" + section_name + "':");
      const std::string where = origin + ": line " + lineOf(entry.first) + ": ";
      if (!entry.second.IsScalar())
        throw Error(where + "setting '" + key + "' must be a single value");
      try {
        setFrom(key, entry.second.Scalar(), origin, where);
      } catch (const Error& e) {
        throw Error(where + e.what());
      }
    }
  }
}

void SettingsSchema::readFile(const std::string& path) const {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open config file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  readYaml(buffer.str(), path);
}

void SettingsSchema::applyOverride(const std::string& key_equals_value) const {
  const auto eq = key_equals_value.find('=');
  if (eq == std::string::npos) {
    throw Error("<flags>: override '" + key_equals_value + "' must be key=value");
  }
  try {
    setFrom(key_equals_value.substr(0, eq), key_equals_value.substr(eq + 1), "<flags>",
            "<flags>: ");
  } catch (const Error& e) {
    throw Error(std::string("<flags>: ") + e.what());
  }
}

void SettingsSchema::validate(const std::string& origin) const {
  for (const auto& b : bindings_) {
    if (!b.validate) continue;
    try {
      b.validate();
    } catch (const Error& e) {
      throw Error(origin + ": " + e.what());
    }
  }
}

std::string SettingsSchema::dump() const {
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> sections;
  for (const auto& b : bindings_) {
    if (b.accepted_only) continue;
    for (const auto& [key, value] : b.entries()) {
      const auto dot = key.find('.');
      sections[key.substr(0, dot)].emplace_back(key.substr(dot + 1), value);
    }
  }
  std::ostringstream out;
  for (const auto& [section, entries] : sections) {
    out << section << ":\n";
    for (const auto& [name, value] : entries) out << "  " << name << ": " << value << "\n";
  }
  return out.str();
}

std::vector<SettingHelp> SettingsSchema::describe() const {
  std::map<std::string, std::vector<SettingHelp>> sections;
  for (const auto& b : bindings_) {
    for (auto& line : b.describe()) {
      sections[line.key.substr(0, line.key.find('.'))].push_back(std::move(line));
    }
  }
  std::vector<SettingHelp> out;
  for (auto& [section, lines] : sections) {
    for (auto& line : lines) out.push_back(std::move(line));
  }
  return out;
}

std::string SettingsSchema::help() const {
  std::ostringstream out;
  for (const auto& s : describe()) {
    out << s.key << " = " << (s.value.empty() ? "\"\"" : s.value) << "  (" << s.expected << ")"
        << (s.recorded_in_model ? " [model]" : "") << "\n    " << s.doc << "\n";
  }
  return out.str();
}

}  // namespace findmug
