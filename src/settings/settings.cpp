// settings.cpp — the settings mechanism shared by every layer (see settings.hpp).
#include "findmug/settings/settings.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <fstream>
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

void SettingsSchema::set(const std::string& key, const std::string& value) const {
  const auto dot = key.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == key.size()) {
    throw Error("setting '" + key + "' must be of the form section.name");
  }
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
    if (!section.second.IsMap()) {
      throw Error(origin + ": line " + lineOf(section.first) + ": section '" + section_name +
                  "' must be a map of settings");
    }
    for (const auto& entry : section.second) {
      const std::string key =
          section_name + "." + keyText(entry.first, origin, "section '" + section_name + "':");
      const std::string where = origin + ": line " + lineOf(entry.first) + ": ";
      if (!entry.second.IsScalar()) throw Error(where + "setting '" + key + "' must be a single value");
      try {
        set(key, entry.second.Scalar());
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
    set(key_equals_value.substr(0, eq), key_equals_value.substr(eq + 1));
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

}  // namespace findmug
