#include "findmug/settings/config.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/settings/settings.hpp"
#include "settings/setting_builders_internal.hpp"

namespace findmug {

const char* classSchemeName(ClassScheme scheme) {
  switch (scheme) {
    case ClassScheme::Nyu13:
      return "nyu13";
    case ClassScheme::Nyu40:
      return "nyu40";
    case ClassScheme::Labels:
      break;
  }
  return "labels";
}

using settings_internal::formatDouble;

void validateSegmenterConfig(const SegmenterConfig& c) {
  if (c.oversegmentation.seed_resolution_m <= c.oversegmentation.voxel_resolution_m) {
    throw Error("oversegmentation.seed_resolution_m (" +
                formatDouble(c.oversegmentation.seed_resolution_m) +
                ") must be larger than oversegmentation.voxel_resolution_m (" +
                formatDouble(c.oversegmentation.voxel_resolution_m) + ")");
  }
  if (c.tables.min_table_height_m >= c.tables.max_table_height_m) {
    throw Error("tables.min_table_height_m must be below tables.max_table_height_m");
  }
  if (c.tables.arm_reach_m <= c.tables.safety_distance_m) {
    throw Error("tables.arm_reach_m (" + formatDouble(c.tables.arm_reach_m) +
                ") must exceed tables.safety_distance_m (" +
                formatDouble(c.tables.safety_distance_m) +
                "): from a search position the arm must reach past the table edge");
  }
  if (c.learner.kind == LearnerKind::XGBoost && c.context.enabled) {
    throw Error(
        "learner.kind = xgboost has no auto-context round; set "
        "features.context = false or learner.kind = forest");
  }
  if (c.tables.min_cluster_points > c.tables.max_cluster_points) {
    throw Error("tables.min_cluster_points must not exceed tables.max_cluster_points");
  }
  validateTableObjectConfig(c.table_objects);
}

void bindCoreSettings(SettingsSchema& schema, Config& config) {
  schema.bind(segmenterSettings(), config.segmenter, validateSegmenterConfig);
}

void bindOfflineSettings(SettingsSchema& schema, Config& config) {
  const SegmenterConfig& segmenter = config.segmenter;
  schema.bind(offlineSettings(), config.offline, [&segmenter](const OfflineConfig& offline) {
    validateOfflineConfig(offline, segmenter);
  });
}

Config parseConfig(const std::string& yaml_text, const std::string& origin) {
  Config config;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  schema.readYaml(yaml_text, origin);
  schema.validate(origin);
  return config;
}

Config loadConfig(const std::string& path) {
  Config config;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  schema.readFile(path);
  schema.validate(path);
  return config;
}

void applyOverride(Config& config, const std::string& key_equals_value) {
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  schema.applyOverride(key_equals_value);
  schema.validate("<flags>");
}

std::string dumpConfig(const Config& config) {
  Config copy = config;
  SettingsSchema schema;
  bindCoreSettings(schema, copy);
  bindOfflineSettings(schema, copy);
  return schema.dump();
}

RandomForest::Settings extractionSettings(const SegmenterConfig& config) {
  RandomForest::Settings out;
  for (const auto& s : segmenterSettings().settings()) {
    if (s.recorded_in_model) out.emplace_back(s.key, s.get(config));
  }
  return out;
}

SegmenterConfig configForModel(SegmenterConfig config, const RandomForest& model) {
  // What the model is (its learner and classes) it holds in its own fields, and the
  // feature-extraction settings as text (models without them were trained in-process).
  RandomForest::Settings recorded = model.extractionSettings();
  recorded.emplace_back("learner.kind", learnerKindName(model.learnerKind()));
  recorded.emplace_back("learner.classes", model.internalClasses().scheme);
  const std::string model_name =
      model.source().empty() ? "forest " + model.id() : "model " + model.source();
  const SettingsTable<SegmenterConfig>& table = segmenterSettings();
  const auto current = table.values(config);
  std::string conflicts;
  bool adopted = false;
  for (const auto& [recorded_key, model_value] : recorded) {
    const std::string key = currentSettingKey(recorded_key);
    const auto it = current.find(key);
    if (it == current.end() || it->second == model_value) continue;
    const auto given = config.given.find(key);
    if (given != config.given.end()) {
      conflicts += "\n  " + key + " = " + it->second + " (" + given->second + ") but " +
                   model_name + " records " + key + " = " + model_value;
      continue;
    }
    try {
      table.set(config, key, model_value);
    } catch (const Error& e) {
      throw Error(model_name + " records a value this build refuses: " + e.what());
    }
    adopted = true;
  }
  if (!conflicts.empty()) {
    throw Error(model_name +
                " was trained with other settings than given; remove the setting to take the "
                "model's value, or retrain:" +
                conflicts);
  }
  if (!adopted) return config;
  try {
    validateSegmenterConfig(config);
  } catch (const Error& e) {
    throw Error("with the settings " + model_name + " records: " + e.what());
  }
  return config;
}

}  // namespace findmug
