// Config: every parameter is a named setting; bad input names the key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "findmug/common/error.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/settings/settings.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Config, EmptyTextGivesDefaults) {
  const Config c = parseConfig("", "empty");
  EXPECT_EQ(c.segmenter.forest.num_trees, ForestParams{}.num_trees);
  EXPECT_FLOAT_EQ(c.segmenter.oversegmentation.seed_resolution_m, 0.1f);
  EXPECT_FLOAT_EQ(c.segmenter.oversegmentation.voxel_resolution_m, 0.01f);
  EXPECT_TRUE(c.segmenter.use_mrf);
}

TEST(Config, ParsesEverySection) {
  const Config c = parseConfig(R"(
forest:
  num_trees: 16
  max_depth: 9
  seed: 123456789012
  bagging_fraction: 0.5
mrf:
  lambda: 2.5
  sigma: 0.3
  enabled: false
oversegmentation:
  method: organized
  seed_resolution_m: 0.15
ground:
  source: floor_labels
tables:
  safety_distance_m: 0.4
)",
                               "test.yaml");
  EXPECT_EQ(c.segmenter.forest.num_trees, 16);
  EXPECT_EQ(c.segmenter.forest.max_depth, 9);
  EXPECT_EQ(c.segmenter.forest.seed, 123456789012ull);
  EXPECT_DOUBLE_EQ(c.segmenter.forest.bagging_fraction, 0.5);
  EXPECT_FLOAT_EQ(c.segmenter.mrf.lambda, 2.5f);
  EXPECT_FLOAT_EQ(c.segmenter.mrf.sigma, 0.3f);
  EXPECT_FALSE(c.segmenter.use_mrf);
  EXPECT_EQ(c.segmenter.oversegmentation.kind, OversegmenterKind::Organized);
  EXPECT_EQ(c.segmenter.ground.source, GroundSource::FloorLabels);
  EXPECT_FLOAT_EQ(c.segmenter.tables.safety_distance_m, 0.4f);
}

TEST(Config, UnknownKeyIsNamed) {
  const auto msg = errorOf([] { parseConfig("forest:\n  num_tres: 3\n", "cfg.yaml"); });
  EXPECT_THAT(msg, HasSubstr("cfg.yaml: line 2: unknown setting 'forest.num_tres' (forest keys: "));
  EXPECT_THAT(msg, HasSubstr("forest.num_trees"));  // the keys that are there
}

TEST(Config, UnknownSectionIsRefused) {
  const auto msg = errorOf([] { parseConfig("forrest:\n  num_trees: 3\n", "cfg.yaml"); });
  EXPECT_THAT(msg, HasSubstr("cfg.yaml: line 2: unknown setting 'forrest.num_trees': no section "
                             "'forrest'"));
  // A program that reads only the segmenter's sections does not accept another program's.
  EXPECT_THAT(errorOf([] { parseConfig("daemon:\n  workers: 2\n", "cfg.yaml"); }),
              HasSubstr("no section 'daemon'"));
}

// The seeds (64-bit) and the bagging fraction (open lower end) are settings like the others.
TEST(Config, SeedsAndBaggingFractionAreRangeChecked) {
  EXPECT_THAT(errorOf([] { parseConfig("forest:\n  seed: -1\n", "a.yaml"); }),
              HasSubstr("forest.seed"));
  EXPECT_THAT(errorOf([] { parseConfig("forest:\n  bagging_fraction: 0\n", "a.yaml"); }),
              HasSubstr("'0' for forest.bagging_fraction (expected a number in (0, 1])"));
  EXPECT_EQ(parseConfig("training:\n  degraded_seed: 9007199254740993\n", "a.yaml")
                .offline.training.degraded_seed,
            9007199254740993ull);  // above 2^53: not through a double
}

TEST(Config, BadValuesNameKeyAndValue) {
  EXPECT_THAT(errorOf([] { parseConfig("forest:\n  num_trees: many\n", "a.yaml"); }),
              HasSubstr("'many' for forest.num_trees"));
  EXPECT_THAT(errorOf([] { parseConfig("forest:\n  num_trees: 0\n", "a.yaml"); }),
              HasSubstr("forest.num_trees"));
  EXPECT_THAT(errorOf([] { parseConfig("mrf:\n  sigma: -1\n", "a.yaml"); }),
              HasSubstr("mrf.sigma"));
  EXPECT_THAT(errorOf([] { parseConfig("mrf:\n  lambda: nan\n", "a.yaml"); }),
              HasSubstr("mrf.lambda"));
  EXPECT_THAT(errorOf([] { parseConfig("mrf:\n  enabled: maybe\n", "a.yaml"); }),
              HasSubstr("mrf.enabled"));
  EXPECT_THAT(errorOf([] { parseConfig("oversegmentation:\n  method: slic\n", "a.yaml"); }),
              HasSubstr("one of pcl organized"));
  EXPECT_THAT(errorOf([] { parseConfig("forest: [1, 2]\n", "a.yaml"); }),
              HasSubstr("section 'forest'"));
  EXPECT_THAT(errorOf([] { parseConfig("forest:\n  num_trees: [1]\n", "a.yaml"); }),
              HasSubstr("forest.num_trees"));
  EXPECT_THAT(errorOf([] { parseConfig("forest: {num_trees: 3", "a.yaml"); }),
              HasSubstr("not valid YAML"));
}

// Issue 10's settings: the scene feature group and the training levers.
TEST(Config, SceneAndTrainingSettings) {
  const Config c = parseConfig(
      "features:\n  scene: true\n  scene_cell_m: 0.2\n  scene_band_px: 10\n"
      "training:\n  sample_weight: sqrt_pixels\n  extra_oversegmentations: 2\n"
      "  extra_seed_scale: 0.9\n  split_labels: nyu40\n",
      "t.yaml");
  EXPECT_TRUE(c.segmenter.scene.enabled);
  EXPECT_FLOAT_EQ(c.segmenter.scene.cell_m, 0.2f);
  EXPECT_EQ(c.segmenter.scene.band_px, 10);
  EXPECT_EQ(c.offline.training.sample_weight, SampleWeighting::SqrtPixels);
  EXPECT_EQ(c.offline.training.extra_oversegmentations, 2);
  EXPECT_FLOAT_EQ(c.offline.training.extra_seed_scale, 0.9f);
  EXPECT_EQ(c.offline.training.split_labels, SplitLabels::Nyu40);
  EXPECT_EQ(OfflineConfig{}.training.split_labels, SplitLabels::Labels);
  EXPECT_EQ(
      parseConfig("training:\n  split_labels: nyu13\n", "a.yaml").offline.training.split_labels,
      SplitLabels::Nyu13);
  EXPECT_THAT(errorOf([] { parseConfig("training:\n  split_labels: nyu894\n", "a.yaml"); }),
              HasSubstr("one of labels nyu40 nyu13"));
  EXPECT_THAT(errorOf([] { parseConfig("training:\n  sample_weight: area\n", "a.yaml"); }),
              HasSubstr("one of patches pixels sqrt_pixels"));
  EXPECT_THAT(errorOf([] { parseConfig("features:\n  scene_band_px: 0\n", "a.yaml"); }),
              HasSubstr("features.scene_band_px"));
  EXPECT_THAT(errorOf([] { parseConfig("training:\n  extra_seed_scale: 1\n", "a.yaml"); }),
              HasSubstr("training.extra_seed_scale"));
  // The scene switches shape the features and go into the model; training.* does not.
  const auto recorded = extractionSettings(c.segmenter);
  auto has = [&](const std::string& key) {
    for (const auto& kv : recorded)
      if (kv.first == key) return true;
    return false;
  };
  EXPECT_TRUE(has("features.scene"));
  EXPECT_TRUE(has("features.scene_band_px"));
  EXPECT_FALSE(has("training.sample_weight"));
  EXPECT_FALSE(has("training.extra_oversegmentations"));
  EXPECT_FALSE(has("training.split_labels"));
}

// The settings only training and evaluation read are their own table, not the
// segmenter's: what a frame goes through at run time cannot depend on them.
TEST(Config, OfflineSettingsAreNotTheSegmenters) {
  for (const char* section : {"training", "degrade", "table_metrics"}) {
    EXPECT_FALSE(segmenterSettings().holds(section)) << section;
    EXPECT_TRUE(offlineSettings().holds(section)) << section;
  }
  for (const char* section : {"forest", "mrf", "tables", "features", "learner"})
    EXPECT_FALSE(offlineSettings().holds(section)) << section;
  // A program that binds only the segmenter's table refuses training.* as unknown,
  // and one that accepts the offline table checks its keys without using them.
  Config segmenter_only;
  SettingsSchema schema;
  bindCoreSettings(schema, segmenter_only);
  EXPECT_THAT(errorOf([&] { schema.readYaml("training:\n  pseudo_rounds: 2\n", "s.yaml"); }),
              HasSubstr("'training'"));
  schema.accept(offlineSettings());
  schema.readYaml("training:\n  pseudo_rounds: 2\ndegrade:\n  quantise: false\n", "s.yaml");
  EXPECT_THAT(errorOf([&] { schema.readYaml("degrade:\n  quantize: false\n", "s.yaml"); }),
              HasSubstr("unknown setting 'degrade.quantize'"));
  EXPECT_EQ(segmenter_only.offline.training.pseudo_rounds, 0);  // accepted, not bound
  // The one rule across the two tables is checked where both are bound.
  EXPECT_THAT(errorOf([] {
                parseConfig("learner:\n  classes: nyu13\ntraining:\n  split_labels: nyu40\n",
                            "c.yaml");
              }),
              HasSubstr("learner.classes = nyu13 cannot be combined with training.split_labels"));
  const Config both = parseConfig(
      "training:\n  pseudo_rounds: 2\ndegrade:\n  quantise: false\n"
      "table_metrics:\n  min_iou: 0.4\n",
      "c.yaml");
  EXPECT_EQ(both.offline.training.pseudo_rounds, 2);
  EXPECT_FALSE(both.offline.degrade.quantise);
  EXPECT_FLOAT_EQ(both.offline.table_metrics.min_iou, 0.4f);
}

TEST(Config, InconsistentResolutionsRefused) {
  const auto msg = errorOf([] {
    parseConfig("oversegmentation:\n  voxel_resolution_m: 0.2\n  seed_resolution_m: 0.1\n",
                "a.yaml");
  });
  EXPECT_THAT(msg, HasSubstr("oversegmentation.seed_resolution_m"));
}

TEST(Config, ObjectConsistencyIsAShareOfOne) {
  const Config c = parseConfig(
      "features:\n  objects: true\nmrf:\n  object_consistency: 0.5\n", "a.yaml");
  EXPECT_FLOAT_EQ(c.segmenter.mrf.object_consistency, 0.5f);
  EXPECT_FLOAT_EQ(Config{}.segmenter.mrf.object_consistency, 0.0f);  // the paper's unaries
  // Without object features it has nothing to act on, and is accepted (the
  // shipped file with a model that has none).
  EXPECT_NO_THROW(parseConfig("mrf:\n  object_consistency: 0.5\n", "a.yaml"));
  EXPECT_THAT(errorOf([] { parseConfig("mrf:\n  object_consistency: 1.5\n", "a.yaml"); }),
              HasSubstr("mrf.object_consistency"));
}

TEST(Config, ObjectColumnsAreOneOfTheirSets) {
  const Config c = parseConfig("features:\n  objects: true\n  objects_columns: relations\n", "a.yaml");
  EXPECT_EQ(c.segmenter.objects.columns, ObjectColumns::Relations);
  EXPECT_EQ(Config{}.segmenter.objects.columns, ObjectColumns::All);
  const std::string error =
      errorOf([] { parseConfig("features:\n  objects_columns: relation\n", "a.yaml"); });
  EXPECT_THAT(error, HasSubstr("features.objects_columns"));
  EXPECT_THAT(error, HasSubstr("relations"));  // the choices are named
}

TEST(Config, ForestShrinkageIsANonNegativeNumber) {
  EXPECT_EQ(Config{}.segmenter.forest.shrinkage, 0.0);  // the paper's leaves
  EXPECT_EQ(parseConfig("forest:\n  shrinkage: 20\n", "a.yaml").segmenter.forest.shrinkage, 20.0);
  EXPECT_THAT(errorOf([] { parseConfig("forest:\n  shrinkage: -1\n", "a.yaml"); }),
              HasSubstr("forest.shrinkage"));
}

TEST(Config, DepthFillIsOffByDefaultAndRangeChecked) {
  EXPECT_EQ(Config{}.segmenter.depth_holes.max_run_px, 0);  // the paper fills nothing
  const Config c = parseConfig(
      "cloud:\n  fill_depth_max_run_px: 40\n  fill_depth_smooth_tolerance: 0.05\n", "a.yaml");
  EXPECT_EQ(c.segmenter.depth_holes.max_run_px, 40);
  EXPECT_FLOAT_EQ(c.segmenter.depth_holes.smooth_tolerance, 0.05f);
  EXPECT_THAT(errorOf([] { parseConfig("cloud:\n  fill_depth_max_run_px: -3\n", "a.yaml"); }),
              HasSubstr("cloud.fill_depth_max_run_px"));
  EXPECT_THAT(
      errorOf([] { parseConfig("cloud:\n  fill_depth_smooth_tolerance: 1.5\n", "a.yaml"); }),
      HasSubstr("cloud.fill_depth_smooth_tolerance"));
}

TEST(Config, OverridesApplyOnTop) {
  Config c = parseConfig("forest:\n  num_trees: 4\n", "a.yaml");
  applyOverride(c, "forest.num_trees=12");
  EXPECT_EQ(c.segmenter.forest.num_trees, 12);
  EXPECT_THAT(errorOf([&] { applyOverride(c, "forest.num_tres=3"); }),
              HasSubstr("<flags>: unknown setting 'forest.num_tres'"));
  EXPECT_THAT(errorOf([&] { applyOverride(c, "forest.num_trees"); }), HasSubstr("key=value"));
  EXPECT_THAT(errorOf([&] { applyOverride(c, "bogus=1"); }), HasSubstr("section.name"));
}

TEST(Config, DumpRoundTrips) {
  Config c = parseConfig(
      "forest:\n  num_trees: 7\n  seed: 99\nmrf:\n  sigma: 0.25\noverseg:\n  method: organized\n"
      "ground:\n  source: estimated\n",
      "a.yaml");
  const Config again = parseConfig(dumpConfig(c), "dump");
  EXPECT_EQ(dumpConfig(again), dumpConfig(c));
  EXPECT_EQ(again.segmenter.forest.num_trees, 7);
  EXPECT_EQ(again.segmenter.forest.seed, 99u);
  EXPECT_EQ(again.segmenter.oversegmentation.kind, OversegmenterKind::Organized);
  EXPECT_EQ(again.segmenter.ground.source, GroundSource::Estimated);
}

TEST(Config, LoadConfigNamesMissingFile) {
  EXPECT_THAT(errorOf([] { loadConfig("/nonexistent/findmugd.yaml"); }),
              HasSubstr("/nonexistent/findmugd.yaml"));
}

// Found by fuzzing (tests/fuzz/regressions/config_yaml): a map or list used as
// a key escaped as a yaml-cpp exception and aborted the daemon at start-up.
TEST(Config, NonScalarKeysAreErrorsNamingTheLine) {
  for (const std::string yaml : {"? [cloud, x]\n: {max_depth_m: 3}\n",
                                 "cloud:\n  ? {a: b}\n  : 3\n"}) {
    try {
      parseConfig(yaml, "bad.yaml");
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const Error& e) {
      EXPECT_THAT(e.what(), HasSubstr("bad.yaml: line "));
      EXPECT_THAT(e.what(), HasSubstr("key must be a plain name"));
    }
  }
}

}  // namespace
}  // namespace findmug
