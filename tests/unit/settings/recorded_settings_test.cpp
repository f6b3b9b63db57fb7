// The settings a model records (Setting::recorded_in_model) and the doc line of every
// core setting: the recorded keys, their order and their text are what the shipped
// models hold, so a change here would make them unloadable or a retrained model differ.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "findmug/map/object_map.hpp"
#include "findmug/map/object_search.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/map/table_map.hpp"
#include "findmug/objects/object_matcher.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/settings/offline_settings.hpp"
#include "findmug/settings/settings.hpp"
#include "shipped_model.hpp"

namespace findmug {
namespace {

// Every key a model records, in the order the model file holds them.
const std::vector<std::string> kRecordedKeys = {
    "cloud.max_depth_m",
    "normals.window_radius_px",
    "normals.smoothing_radius_px",
    "normals.max_depth_jump_m",
    "oversegmentation.method",
    "oversegmentation.voxel_resolution_m",
    "oversegmentation.seed_resolution_m",
    "oversegmentation.color_importance",
    "oversegmentation.spatial_importance",
    "oversegmentation.normal_importance",
    "oversegmentation.min_segment_points",
    "oversegmentation.max_iterations",
    "oversegmentation.organized_seed_density",
    "oversegmentation.search_window_factor",
    "features.regions",
    "features.region_normal_angle_deg",
    "features.region_plane_distance_m",
    "features.scene",
    "features.scene_cell_m",
    "features.scene_band_px",
    "features.objects",
    "features.objects_columns",
    "features.objects_concave_tolerance_deg",
    "features.objects_link_gap_m",
    "features.objects_step_m",
    "features.objects_convex_margin",
    "features.objects_floor_height_m",
    "features.objects_plane_min_area_m2",
    "features.objects_orientation_tolerance_deg",
    "features.context",
    "features.context_near_m",
    "features.context_far_m",
    "features.context_column_radius_m",
};

std::vector<std::string> keysOf(const RandomForest::Settings& settings) {
  std::vector<std::string> keys;
  for (const auto& [key, value] : settings) keys.push_back(currentSettingKey(key));
  return keys;
}

// A model's recorded settings under the keys' current names (models trained before a
// rename keep the old ones: overseg.* in the shipped models).
RandomForest::Settings underCurrentNames(RandomForest::Settings settings) {
  for (auto& [key, value] : settings) key = currentSettingKey(key);
  return settings;
}

TEST(RecordedSettings, TheFlaggedKeysAreTheRecordedOnesInTableOrder) {
  EXPECT_EQ(keysOf(extractionSettings(SegmenterConfig{})), kRecordedKeys);
  std::vector<std::string> flagged;
  for (const auto& s : segmenterSettings().settings()) {
    if (s.recorded_in_model) flagged.push_back(s.key);
  }
  EXPECT_EQ(flagged, kRecordedKeys);
  // Neither the depth fill nor the training-only cross-fitting is recorded.
  for (const auto& s : segmenterSettings().settings()) {
    if (s.key.rfind("cloud.fill_depth_", 0) == 0 || s.key == "features.context_cross_fit_folds") {
      EXPECT_FALSE(s.recorded_in_model) << s.key;
    }
  }
  for (const auto& s : offlineSettings().settings()) EXPECT_FALSE(s.recorded_in_model) << s.key;
}

// The values as text: the float widened to double with 9 digits, as every model holds them.
TEST(RecordedSettings, ValuesKeepTheModelFilesText) {
  const auto recorded = extractionSettings(SegmenterConfig{});
  ASSERT_EQ(recorded.size(), kRecordedKeys.size());
  EXPECT_EQ(recorded[0], (std::pair<std::string, std::string>{"cloud.max_depth_m", "10"}));
  EXPECT_EQ(recorded[5], (std::pair<std::string, std::string>{
                             "oversegmentation.voxel_resolution_m", "0.00999999978"}));
  EXPECT_EQ(recorded[4], (std::pair<std::string, std::string>{"oversegmentation.method", "organized"}));
  EXPECT_EQ(recorded[14], (std::pair<std::string, std::string>{"features.regions", "false"}));
}

// The shipped model holds exactly these keys, and the settings it records, made the
// config's by configForModel, are recorded again as the same text (a retrained model
// records what this one does).
TEST(RecordedSettings, ShippedModelRecordsTheseKeysAndReadsBackTheSameText) {
  const auto model = test::shippedModel();
  EXPECT_EQ(keysOf(model->extractionSettings()), kRecordedKeys);
  const SegmenterConfig config = configForModel(SegmenterConfig{}, *model);
  EXPECT_EQ(extractionSettings(config), underCurrentNames(model->extractionSettings()));
}

template <typename T>
void expectEveryDoc(const SettingsTable<T>& table) {
  EXPECT_FALSE(table.settings().empty());
  for (const auto& s : table.settings()) {
    EXPECT_FALSE(s.doc.empty()) << s.key << " has no doc line";
    EXPECT_EQ(s.doc.find('\n'), std::string::npos) << s.key << ": one line";
    EXPECT_FALSE(s.expected.empty()) << s.key << " does not say what a value must be";
  }
}

// The daemon's, check's and web's own tables are held to the same by the test of
// findmugd --help-settings (FindmugdHelpSettings, daemon_check_test), which lists them all.
TEST(SettingDocs, EveryCoreSettingHasADocLine) {
  expectEveryDoc(segmenterSettings());
  expectEveryDoc(offlineSettings());
  expectEveryDoc(tableMapSettings());
  expectEveryDoc(semanticMapSettings());
  expectEveryDoc(objectMatcherSettings());
  expectEveryDoc(objectMapSettings());
  expectEveryDoc(objectSearchSettings());
}

TEST(SettingDocs, HelpListsKeyDefaultRangeAndDoc) {
  Config config;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  const std::string help = schema.help();
  EXPECT_THAT(help, ::testing::HasSubstr("mrf.lambda = 1  (a number in [0, 1000])\n    "));
  EXPECT_THAT(help, ::testing::HasSubstr(
                        "features.objects = false  (true or false) [model]\n    object features"));
  EXPECT_THAT(help, ::testing::HasSubstr("cloud.fill_depth_max_run_px = 0  (an integer in"));
  EXPECT_THAT(help, ::testing::Not(::testing::HasSubstr("cloud.fill_depth_max_run_px = 0  "
                                                        "(an integer in [0, 10000]) [model]")));
}

}  // namespace
}  // namespace findmug
