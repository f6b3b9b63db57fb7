// settings.cpp — the settings mechanism shared by every layer (see settings.hpp).
#include "findmug/settings/settings.hpp"

#include <charconv>
#include <sstream>

#include "findmug/map/semantic_map.hpp"
#include "findmug/settings/config.hpp"

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

void ConfigSections::addSection(const std::string& name, Check check) {
  if (!check) throw Error("config section '" + name + "': registered without a check");
  const auto it = sections_.find(name);
  if (it != sections_.end() && it->second) {
    throw Error("config section '" + name + "' registered twice");
  }
  sections_[name] = std::move(check);
}

void ConfigSections::addSectionName(const std::string& name) { sections_.try_emplace(name); }

void ConfigSections::check(const std::string& section, const std::string& key,
                           const std::string& value) const {
  const auto it = sections_.find(section);
  if (it == sections_.end()) throw Error("unknown setting '" + key + "'");
  if (it->second) it->second(key, value);
}

ConfigSections& configSections() {
  static ConfigSections sections = [] {
    ConfigSections s;
    // The core's own section outside SegmenterConfig (resolveTableMapConfig).
    s.addSection("table_map", [](const std::string& key, const std::string& value) {
      tableMapSettings().check(key, value);
    });
    // The fused 3-D map's (resolveSemanticMapConfig).
    s.addSection("semantic_map", [](const std::string& key, const std::string& value) {
      semanticMapSettings().check(key, value);
    });
    return s;
  }();
  return sections;
}

}  // namespace findmug
