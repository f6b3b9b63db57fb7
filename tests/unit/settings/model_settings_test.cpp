// A model's recorded settings are the defaults of the keys it records (configForModel):
// the Segmenter runs a model trained with other feature settings with the model's
// values, and refuses a value given explicitly (file or --set) that differs, naming both.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/settings/settings.hpp"
#include "shipped_model.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

// A small forest on the 14 base features, recording `recorded` as findmug-train does,
// saved to `path` and read back (so that it knows its file).
std::shared_ptr<const RandomForest> modelRecording(const SegmenterConfig& recorded,
                                                   const std::string& path) {
  TrainingSet set;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 200; ++i) {
    FeatureVector f{};
    for (auto& v : f) v = u(rng);
    set.features.push_back(f);
    set.labels.push_back(static_cast<std::uint8_t>(f[0] > 0.5f ? 1 : 2));
  }
  ForestParams params;
  params.num_trees = 2;
  params.max_depth = 4;
  RandomForest forest = RandomForest::train(set, params);
  forest.setExtractionSettings(extractionSettings(recorded));
  forest.save(path);
  return std::make_shared<const RandomForest>(RandomForest::load(path));
}

// A model's recorded settings under the keys' current names (models trained before a
// rename keep the old ones: overseg.* in the shipped models).
RandomForest::Settings underCurrentNames(RandomForest::Settings settings) {
  for (auto& [key, value] : settings) key = currentSettingKey(key);
  return settings;
}

// Non-default feature-extraction settings that keep the 14 base columns.
SegmenterConfig otherFeatureSettings() {
  SegmenterConfig c;
  c.oversegmentation.seed_resolution_m = 0.15f;
  c.normals.window_radius_px = 6;
  return c;
}

std::string refusal(const SegmenterConfig& config, std::shared_ptr<const RandomForest> model) {
  try {
    Segmenter segmenter(config, std::move(model));
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ModelSettings, KeysNotGivenTakeTheModelsValues) {
  test::TempDir dir;
  const std::string path = (dir.path() / "other.fmf").string();
  const auto model = modelRecording(otherFeatureSettings(), path);
  // The built-in defaults, and a file that gives none of the recorded keys.
  const Config from_file = parseConfig("mrf:\n  lambda: 2\n", "mine.yaml");
  for (const SegmenterConfig& config : {SegmenterConfig{}, from_file.segmenter}) {
    const Segmenter segmenter(config, model);
    EXPECT_EQ(segmenter.config().oversegmentation.seed_resolution_m, 0.15f);
    EXPECT_EQ(segmenter.config().normals.window_radius_px, 6);
    EXPECT_EQ(extractionSettings(segmenter.config()), model->extractionSettings());
  }
  EXPECT_EQ(Segmenter(from_file.segmenter, model).config().mrf.lambda, 2.0f);
  // Without a model the config is the Segmenter's as given.
  EXPECT_EQ(Segmenter(SegmenterConfig{}, nullptr).config().normals.window_radius_px,
            SegmenterConfig{}.normals.window_radius_px);
}

TEST(ModelSettings, AKeyGivenWithAnotherValueIsRefusedNamingBoth) {
  test::TempDir dir;
  const std::string path = (dir.path() / "other.fmf").string();
  const auto model = modelRecording(otherFeatureSettings(), path);

  const Config from_file =
      parseConfig("mrf:\n  lambda: 2\noversegmentation:\n  seed_resolution_m: 0.2\n", "mine.yaml");
  const std::string file_error = refusal(from_file.segmenter, model);
  EXPECT_THAT(file_error, HasSubstr("oversegmentation.seed_resolution_m = 0.200000003 "
                                    "(mine.yaml: line 4)"));
  EXPECT_THAT(file_error, HasSubstr("model " + path +
                                    " records oversegmentation.seed_resolution_m = 0.150000006"));

  Config from_flags;
  applyOverride(from_flags, "normals.window_radius_px=5");
  const std::string flag_error = refusal(from_flags.segmenter, model);
  EXPECT_THAT(flag_error, HasSubstr("normals.window_radius_px = 5 (--set)"));
  EXPECT_THAT(flag_error, HasSubstr("records normals.window_radius_px = 6"));
  EXPECT_THAT(flag_error, HasSubstr(path));

  // Given explicitly with the model's own value: taken.
  Config same;
  applyOverride(same, "normals.window_radius_px=6");
  EXPECT_NO_THROW(Segmenter(same.segmenter, model));
}

// What the model is, learner.kind and learner.classes, is taken from it in the same way:
// the shipped model (NYU-13 classes, region, scene and object features) runs with the
// built-in defaults, and a conflicting learner.classes given is refused naming both.
TEST(ModelSettings, TheShippedModelRunsWithTheBuiltInDefaults) {
  const auto model = test::shippedModel();
  const Segmenter segmenter(SegmenterConfig{}, model);
  EXPECT_EQ(segmenter.config().learner.classes, ClassScheme::Nyu13);
  EXPECT_TRUE(segmenter.config().regions.enabled);
  EXPECT_TRUE(segmenter.config().objects.enabled);
  EXPECT_EQ(extractionSettings(segmenter.config()), underCurrentNames(model->extractionSettings()));

  Config labels;
  applyOverride(labels, "learner.classes=labels");
  const std::string error = refusal(labels.segmenter, model);
  EXPECT_THAT(error, HasSubstr("learner.classes = labels (--set)"));
  EXPECT_THAT(error, HasSubstr("findmug.fmf records learner.classes = nyu13"));
}

// A program's own changes to the struct (not read from a file or a flag) are no
// explicit setting: the model's value wins.
TEST(ModelSettings, OnlyTheFileAndTheFlagsAreExplicit) {
  SettingsSchema schema;
  Config config;
  bindCoreSettings(schema, config);
  schema.readYaml("normals:\n  max_depth_jump_m: 0.04\n", "a.yaml");
  schema.applyOverride("mrf.sigma=0.2");
  EXPECT_EQ(config.segmenter.given.at("normals.max_depth_jump_m"), "a.yaml: line 2");
  EXPECT_EQ(config.segmenter.given.at("mrf.sigma"), "--set");
  EXPECT_EQ(config.segmenter.given.count("normals.window_radius_px"), 0u);
}

}  // namespace
}  // namespace findmug
