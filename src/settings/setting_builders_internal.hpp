// setting_builders_internal.hpp — how the core's settings tables declare a setting
// (src/settings/segmenter_settings.cpp, offline_settings.cpp): the mechanism's
// builders (findmug/settings/settings.hpp) with the core's defaults, the doc line and
// the recorded-in-model flag set where a setting is declared, and a table made of a list.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "findmug/settings/config.hpp"
#include "findmug/settings/settings.hpp"

namespace findmug::settings_internal {

// One named setting of the segmenter (the shared mechanism, settings.hpp).
using CoreSetting = Setting<SegmenterConfig>;

inline std::string formatDouble(double v) { return formatSettingNumber(v); }

// Builders for the kinds of settings, with inclusive ranges (settings.hpp), for
// the segmenter's table (T defaults to SegmenterConfig) and the offline one.
template <typename T = SegmenterConfig>
inline Setting<T> floatSetting(std::string key,
                               std::type_identity_t<std::function<float&(T&)>> field, double lo,
                               double hi) {
  Setting<T> s = numberSetting<T, float>(std::move(key), field, lo, hi);
  // Printed as the float widened to double with 9 digits ("0.00999999978"):
  // models store the feature settings in this text (extractionSettings) and
  // are compared with it, so it must not change.
  s.get = [field](const T& c) { return formatDouble(field(const_cast<T&>(c))); };
  return s;
}

template <typename T = SegmenterConfig>
Setting<T> intSetting(std::string key, std::type_identity_t<std::function<int&(T&)>> field,
                      long long lo, long long hi) {
  return integerSetting<T, int>(std::move(key), std::move(field), lo, hi);
}

inline CoreSetting doubleSetting(std::string key, std::function<double&(SegmenterConfig&)> field,
                                 double lo, double hi) {
  return numberSetting<SegmenterConfig, double>(std::move(key), std::move(field), lo, hi);
}

template <typename T = SegmenterConfig>
Setting<T> boolSetting(std::string key, std::type_identity_t<std::function<bool&(T&)>> field) {
  return findmug::boolSetting<T>(std::move(key), std::move(field));
}

template <typename Enum, typename T = SegmenterConfig>
Setting<T> enumSetting(std::string key, std::type_identity_t<std::function<Enum&(T&)>> field,
                       std::vector<std::pair<std::string, Enum>> names) {
  return findmug::enumSetting<T, Enum>(std::move(key), std::move(field), std::move(names));
}

template <typename T = SegmenterConfig>
Setting<T> seedSetting(std::string key,
                       std::type_identity_t<std::function<std::uint64_t&(T&)>> field) {
  return integerSetting<T, std::uint64_t>(std::move(key), std::move(field), 0,
                                          std::numeric_limits<long long>::max());
}

// `setting`, recorded in the model file (Setting::recorded_in_model): the
// feature-extraction settings, whose values decide what a feature means. Which gaps
// the depth fill closes (cloud.fill_depth_*) only decides which pixels have points,
// so a model serves filled and raw depth alike; features.context_cross_fit_folds
// only shapes training. Neither is recorded.
template <typename T>
Setting<T> recorded(Setting<T> setting) {
  setting.recorded_in_model = true;
  return setting;
}

// `setting` with its doc line (the listing of --help style tools).
template <typename T>
Setting<T> documented(Setting<T> setting, std::string doc) {
  setting.doc = std::move(doc);
  return setting;
}

// A table over every section its settings name, in the order they first appear.
template <typename T>
SettingsTable<T> tableOf(const std::vector<Setting<T>>& list) {
  std::vector<std::string> sections;
  for (const auto& s : list) {
    const std::string section = SettingsTable<T>::sectionOf(s.key);
    if (std::find(sections.begin(), sections.end(), section) == sections.end()) {
      sections.push_back(section);
    }
  }
  SettingsTable<T> t(std::move(sections));
  for (const auto& s : list) t.add(s);
  return t;
}

}  // namespace findmug::settings_internal
