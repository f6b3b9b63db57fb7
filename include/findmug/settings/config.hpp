// findmug/settings/config.hpp — every tunable parameter, one YAML file plus overrides.
//
// Keys are `section.name` (e.g. `forest.num_trees`, `mrf.lambda`,
// `oversegmentation.seed_resolution_m`, `tables.safety_distance_m`). Unknown keys and
// bad values are errors that name the key. The segmenter's sections are one
// SettingsTable (segmenterSettings); a program binds it, and the other tables
// it reads, into a SettingsSchema (settings.hpp). parseConfig/loadConfig read
// a file of the segmenter's sections only (tests, tools that read no other).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/features/context_features.hpp"
#include "findmug/features/object_features.hpp"
#include "findmug/features/region_features.hpp"
#include "findmug/features/scene_features.hpp"
#include "findmug/frame/depth_holes.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/labels/label_holes.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/mrf/mrf.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "findmug/settings/offline_settings.hpp"
#include "findmug/settings/settings.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {

// The classes the model learns (learner.classes); the model merges them into
// the 8 labels. Recorded in the model, which gives it unless the config does
// (configForModel). Supersedes nothing: training.split_labels (finer classes
// for the forest's splits only, weighting by label) stays as it was, and the
// two cannot be combined.
enum class ClassScheme {
  Labels,  // the 8 findmug labels (the paper's)
  Nyu13,   // NYU-13 class x findmug label pairs (needs label13/)
  Nyu40,   // NYU-40 classes (needs label40/ or the .mat file)
};
const char* classSchemeName(ClassScheme scheme);  // "labels", "nyu13", "nyu40"

// What learner.class_weighting balances when the model has internal classes
// (learner.class_weight; training only, not recorded in the model).
enum class ClassWeight {
  Labels,   // every label carries the same total weight, its internal classes
            // in proportion to their frequency (the 8-class model's balance)
  Classes,  // every internal class carries the same total weight (a label made
            // of many internal classes, e.g. unknown, then weighs more)
};

struct LearnerOptions {
  LearnerKind kind = LearnerKind::Forest;          // learner.kind
  ClassScheme classes = ClassScheme::Labels;       // learner.classes
  ClassWeight class_weight = ClassWeight::Labels;  // learner.class_weight
};

struct SegmenterConfig {
  float max_depth_m = 10.0f;
  DepthHoleFillConfig depth_holes;  // cloud.fill_depth_*
  NormalConfig normals;
  GroundConfig ground;
  OversegmentationConfig oversegmentation;
  RegionConfig regions;   // features.regions, features.region_*
  SceneConfig scene;      // features.scene, features.scene_*
  ObjectConfig objects;   // features.objects, features.objects_*
  ContextConfig context;  // features.context, features.context_*
  ForestParams forest;
  LearnerOptions learner;  // learner.*
  XGBoostParams xgboost;   // xgboost.* (learner.kind = xgboost)
  MrfParams mrf;
  bool use_mrf = true;
  LabelHoleFillConfig label_holes;  // labels.*
  TableConfig tables;
  TableObjectConfig table_objects;  // table_objects.*
  // The keys a settings file or a --set gave, and where (SettingsSchema::bind fills
  // it): of the keys a model records, these are the only ones it does not set
  // (configForModel).
  SettingOrigins given;
};

// The core's sections of a settings file: what the segmenter runs with, and what
// only the offline tools read (findmug/settings/offline_settings.hpp). The daemon
// and the clients bind `segmenter` and accept the offline sections unread.
struct Config {
  SegmenterConfig segmenter;
  OfflineConfig offline;  // training.*, degrade.*, table_metrics.*
};

// The segmenter's sections (cloud, normals, ground, oversegmentation, features, forest,
// learner, xgboost, mrf, labels, tables): one table.
const SettingsTable<SegmenterConfig>& segmenterSettings();
// The rules across its keys (seed above voxel resolution, ...); throws Error naming them.
void validateSegmenterConfig(const SegmenterConfig& config);
// Binds segmenterSettings() with validateSegmenterConfig to `config.segmenter`.
void bindCoreSettings(SettingsSchema& schema, Config& config);
// Binds offlineSettings() to `config.offline`, checked against `config.segmenter`
// (validateOfflineConfig): findmug-train, findmug-eval and the tools that train.
void bindOfflineSettings(SettingsSchema& schema, Config& config);

// Parses YAML text of the core's sections (the segmenter's and the offline ones);
// `origin` names it in errors (file path).
Config parseConfig(const std::string& yaml_text, const std::string& origin);
Config loadConfig(const std::string& path);
// Applies one "key=value" override (a --set flag) on top.
void applyOverride(Config& config, const std::string& key_equals_value);
// The segmenter's effective settings as YAML (reports; SettingsSchema::dump for a whole program).
std::string dumpConfig(const Config& config);

// The settings recorded in a model (Setting::recorded_in_model: the feature-extraction
// settings cloud.max_depth_m, normals.*, oversegmentation.*, features.* but
// features.context_cross_fit_folds), as "key" -> "value" in the table's order. The
// trainer stores them in the model; a model runs only with the same values
// (configForModel, checkModelMatchesConfig).
RandomForest::Settings extractionSettings(const SegmenterConfig& config);

// `config` with the values `model` records (RandomForest::extractionSettings, keys
// under their current names, and what the model is: learner.kind, learner.classes) for
// every key `config.given` does not hold: a model's recorded settings are the defaults
// of the keys it records. A key given explicitly
// with another value is an Error naming the key, the value given and where, the
// model's value and the model. Keys unknown to this build are left to
// checkModelMatchesConfig; the cross-key rules (validateSegmenterConfig) are checked
// on the result.
SegmenterConfig configForModel(SegmenterConfig config, const RandomForest& model);

}  // namespace findmug
