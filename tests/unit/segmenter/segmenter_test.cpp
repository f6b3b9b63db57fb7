// Segmenter: the stages chained for one frame, on a scene whose answer is known.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <set>

#include "findmug/common/error.hpp"
#include "findmug/offline/metrics.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "small_forest.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

// A camera 1.2 m above a floor, pitched 30 degrees down, facing a wall 3 m
// ahead. Floor is grey-brown, wall light blue. Returns the frame and, per
// pixel, the true label (floor / wall, void where no depth).
struct Scene {
  RgbdFrame frame;
  std::vector<std::uint8_t> truth;
};

Scene floorAndWall(bool with_extrinsics) {
  Scene s;
  RgbdFrame& f = s.frame;
  f.width = 320;
  f.height = 240;
  f.intrinsics = {262.5, 262.5, 159.5, 119.5};
  f.source = "synthetic floor+wall";
  const double h = 1.2, pitch = 30.0 * M_PI / 180.0, wall_x = 3.0;
  if (with_extrinsics) f.extrinsics = CameraExtrinsics{h, pitch, 0.0};
  f.depth_mm.assign(f.width * f.height, 0);
  f.rgb.assign(f.width * f.height, Rgb8{});
  s.truth.assign(f.width * f.height, kVoidLabel);
  for (int v = 0; v < f.height; ++v) {
    for (int u = 0; u < f.width; ++u) {
      // Ray in camera optical frame, then in a world frame with x forward, z up.
      const double xc = (u - f.intrinsics.cx) / f.intrinsics.fx;
      const double yc = (v - f.intrinsics.cy) / f.intrinsics.fy;
      const double fwd = std::cos(pitch) * 1.0 - std::sin(pitch) * yc;   // along x (world)
      const double up = -std::sin(pitch) * 1.0 - std::cos(pitch) * yc;   // along z (world)
      double t_floor = up < 0 ? h / -up : INFINITY;
      double t_wall = fwd > 0 ? wall_x / fwd : INFINITY;
      const double t = std::min(t_floor, t_wall);
      if (!std::isfinite(t) || t > 8.0) continue;
      const std::size_t i = static_cast<std::size_t>(v) * f.width + u;
      f.depth_mm[i] = static_cast<std::uint16_t>(std::lround(t * 1000.0));  // z = t (unit z ray)
      const bool floor = t_floor < t_wall;
      s.truth[i] = static_cast<std::uint8_t>(floor ? Label::Floor : Label::Wall);
      f.rgb[i] = floor ? Rgb8{120, 100, 80} : Rgb8{170, 190, 230};
      (void)xc;
    }
  }
  return s;
}

std::shared_ptr<const RandomForest> trainOn(const Segmenter& segmenter, const Scene& scene) {
  return test::trainSmallForest(segmenter, scene.frame, scene.truth);
}

SegmenterConfig fastConfig() {
  SegmenterConfig config;
  config.oversegmentation.kind = OversegmenterKind::Organized;
  return config;
}

TEST(Segmenter, LabelsAKnownSceneCorrectly) {
  const Scene scene = floorAndWall(true);
  const Segmenter untrained(fastConfig(), nullptr);
  const auto forest = trainOn(untrained, scene);
  const Segmenter segmenter(fastConfig(), forest);

  const LabelledFrame out = segmenter.process(scene.frame);
  ASSERT_EQ(out.labels.width, scene.frame.width);
  ASSERT_EQ(out.labels.height, scene.frame.height);
  ASSERT_EQ(out.labels.labels.size(), scene.truth.size());
  ConfusionMatrix cm;
  cm.add(scene.truth, out.labels.labels);
  EXPECT_GT(cm.globalAccuracy(), 0.9);
  EXPECT_GT(cm.perClassAccuracy()[static_cast<int>(Label::Floor)], 0.9);
  EXPECT_GT(cm.perClassAccuracy()[static_cast<int>(Label::Wall)], 0.9);
  // Where there is no depth, a label is only filled in, with no confidence
  // (labels.fill_holes, FillsTheLabelImagesDepthHoles below).
  for (std::size_t i = 0; i < scene.truth.size(); ++i) {
    if (scene.frame.depth_mm[i] == 0) {
      ASSERT_EQ(out.labels.confidence[i], 0.0f) << i;
    }
  }
  // The stages report their own time.
  EXPECT_GT(out.timings.total(), 0.0);
  EXPECT_EQ(out.forest_labels.size(), out.features.features.size());
  EXPECT_EQ(out.mrf.labels.size(), out.features.features.size());
}

// A raw camera's holes: a blob on the wall (a dark poster) and a shadow run
// beside nothing in particular on the floor. With labels.fill_holes they take
// the label around them with confidence 0; without it they stay void; the
// patches, their labels and the tables do not change either way.
TEST(Segmenter, FillsTheLabelImagesDepthHoles) {
  Scene scene = floorAndWall(true);
  const Segmenter untrained(fastConfig(), nullptr);
  const auto forest = trainOn(untrained, scene);
  std::vector<std::size_t> holes;
  const auto punch = [&](int u0, int v0, int w, int h) {
    for (int v = v0; v < v0 + h; ++v) {
      for (int u = u0; u < u0 + w; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * scene.frame.width + u;
        ASSERT_NE(scene.frame.depth_mm[i], 0);
        scene.frame.depth_mm[i] = 0;
        holes.push_back(i);
      }
    }
  };
  punch(150, 30, 12, 8);  // on the wall, rows 30-37
  punch(100, 200, 9, 1);  // a shadow run on the floor
  for (std::size_t i : holes) ASSERT_NE(scene.truth[i], kVoidLabel);

  SegmenterConfig fill = fastConfig();
  SegmenterConfig no_fill = fastConfig();
  no_fill.label_holes.enabled = false;
  const LabelledFrame filled = Segmenter(fill, forest).process(scene.frame);
  const LabelledFrame unfilled = Segmenter(no_fill, forest).process(scene.frame);
  for (std::size_t i : holes) {
    ASSERT_EQ(unfilled.labels.labels[i], kVoidLabel) << i;
    ASSERT_EQ(filled.labels.labels[i], scene.truth[i]) << i;
    ASSERT_EQ(filled.labels.confidence[i], 0.0f) << i;
  }
  EXPECT_EQ(filled.mrf.labels, unfilled.mrf.labels);
  EXPECT_EQ(filled.tables.size(), unfilled.tables.size());
  ConfusionMatrix with, without;
  with.add(scene.truth, filled.labels.labels);
  without.add(scene.truth, unfilled.labels.labels);
  EXPECT_GT(with.globalAccuracy(), without.globalAccuracy());
}

TEST(Segmenter, GroundFromExtrinsicsPutsFloorAtZeroHeight) {
  const Scene scene = floorAndWall(true);
  const Segmenter segmenter(fastConfig(), nullptr);
  const PreparedFrame prepared = segmenter.prepare(scene.frame);
  ASSERT_TRUE(prepared.ground.has_value());
  int checked = 0;
  for (std::size_t i = 0; i < scene.truth.size(); i += 97) {
    if (scene.truth[i] != static_cast<std::uint8_t>(Label::Floor)) continue;
    EXPECT_NEAR(prepared.cloud_ground.points[i].z(), 0.0f, 0.01f);
    ++checked;
  }
  EXPECT_GT(checked, 50);
}

TEST(Segmenter, EstimatedGroundMatchesExtrinsics) {
  const Scene scene = floorAndWall(false);
  SegmenterConfig config = fastConfig();
  config.ground.source = GroundSource::Estimated;
  const Segmenter segmenter(config, nullptr);
  const PreparedFrame prepared = segmenter.prepare(scene.frame);
  ASSERT_TRUE(prepared.ground.has_value());
  const GroundPlane truth = groundFromExtrinsics(CameraExtrinsics{1.2, 30.0 * M_PI / 180.0, 0.0});
  EXPECT_GT(prepared.ground->normal_camera.dot(truth.normal_camera), std::cos(2.0 * M_PI / 180.0));
  EXPECT_NEAR(prepared.ground->offset, truth.offset, 0.03);
}

TEST(Segmenter, FloorLabelGroundNeedsGroundTruth) {
  const Scene scene = floorAndWall(false);
  SegmenterConfig config = fastConfig();
  config.ground.source = GroundSource::FloorLabels;
  const Segmenter segmenter(config, nullptr);
  EXPECT_THROW(segmenter.prepare(scene.frame), Error);
  const PreparedFrame prepared = segmenter.prepare(scene.frame, &scene.truth);
  EXPECT_TRUE(prepared.ground.has_value());
}

TEST(Segmenter, ExtrinsicsSourceRefusesFrameWithout) {
  const Scene scene = floorAndWall(false);
  SegmenterConfig config = fastConfig();
  config.ground.source = GroundSource::Extrinsics;
  const Segmenter segmenter(config, nullptr);
  try {
    segmenter.prepare(scene.frame);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("synthetic floor+wall"));
    EXPECT_THAT(e.what(), HasSubstr("extrinsics"));
  }
}

TEST(Segmenter, ClassifyWithoutForestIsAnError) {
  const Scene scene = floorAndWall(true);
  const Segmenter segmenter(fastConfig(), nullptr);
  EXPECT_THROW(segmenter.process(scene.frame), Error);
}

TEST(Segmenter, FrameWithoutGroundGetsAllVoidLabels) {
  // A wall only (camera looking straight at it): no floor to estimate.
  Scene scene = floorAndWall(false);
  for (std::size_t i = 0; i < scene.truth.size(); ++i) {
    scene.frame.depth_mm[i] = 2000;
    scene.frame.rgb[i] = {170, 190, 230};
  }
  SegmenterConfig config = fastConfig();
  config.ground.source = GroundSource::Estimated;
  const Segmenter untrained(config, nullptr);
  const auto forest = trainOn(Segmenter(fastConfig(), nullptr), floorAndWall(true));
  const Segmenter segmenter(config, forest);
  const LabelledFrame out = segmenter.process(scene.frame);
  EXPECT_FALSE(out.segmented.prepared.ground.has_value());
  ASSERT_EQ(out.labels.labels.size(), scene.truth.size());
  for (auto y : out.labels.labels) ASSERT_EQ(y, kVoidLabel);
}

// The extraction settings a model records are the defaults of their keys: a config that
// does not give them (a file or --set) runs with the model's; one that gives another
// value is refused, naming the key, both values, where the config's came from and the model.
TEST(Segmenter, TakesTheModelsExtractionSettingsAndRefusesOnesGivenOtherwise) {
  const Scene scene = floorAndWall(true);
  SegmenterConfig trained_config = fastConfig();
  auto trained = trainOn(Segmenter(trained_config, nullptr), scene);
  RandomForest forest = *trained;
  forest.setExtractionSettings(extractionSettings(trained_config));
  auto model = std::make_shared<const RandomForest>(forest);

  EXPECT_NO_THROW(Segmenter(trained_config, model));
  SegmenterConfig other = trained_config;
  other.oversegmentation.kind = OversegmenterKind::PclSupervoxels;
  other.oversegmentation.seed_resolution_m = 0.15f;
  const Segmenter taking(other, model);
  EXPECT_EQ(taking.config().oversegmentation.kind, OversegmenterKind::Organized);
  EXPECT_EQ(taking.config().oversegmentation.seed_resolution_m,
            trained_config.oversegmentation.seed_resolution_m);
  EXPECT_EQ(extractionSettings(taking.config()), forest.extractionSettings());

  Config given;
  given.segmenter = trained_config;
  applyOverride(given, "oversegmentation.method=pcl");
  applyOverride(given, "oversegmentation.seed_resolution_m=0.15");
  try {
    Segmenter segmenter(given.segmenter, model);
    FAIL() << "expected the model to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("oversegmentation.method = pcl (--set) but forest " +
                                    forest.id() + " records oversegmentation.method = organized"));
    EXPECT_THAT(e.what(), HasSubstr("oversegmentation.seed_resolution_m = 0.150000006 (--set)"));
  }
  // Settings that do not shape the features (MRF, tables) may differ freely.
  SegmenterConfig mrf_only = trained_config;
  mrf_only.mrf.lambda = 3.0f;
  mrf_only.tables.safety_distance_m = 0.4f;
  EXPECT_NO_THROW(Segmenter(mrf_only, model));
}

// Models trained before the rename of overseg.* record the old key names: they are
// compared under the new names (currentSettingKey), so such a model still runs with
// the settings it was trained with and is still refused with others.
TEST(Segmenter, ModelsRecordingOldKeyNamesAreComparedUnderTheNewNames) {
  const Scene scene = floorAndWall(true);
  const SegmenterConfig trained_config = fastConfig();
  RandomForest forest = *trainOn(Segmenter(trained_config, nullptr), scene);
  RandomForest::Settings recorded = extractionSettings(trained_config);
  int renamed = 0;
  for (auto& [key, value] : recorded) {
    if (key.rfind("oversegmentation.", 0) == 0) {
      key = "overseg." + key.substr(std::string("oversegmentation.").size());
      ++renamed;
    }
  }
  ASSERT_GT(renamed, 5);
  forest.setExtractionSettings(recorded);
  const auto model = std::make_shared<const RandomForest>(forest);
  EXPECT_NO_THROW(Segmenter(trained_config, model));
  Config other;
  other.segmenter = trained_config;
  applyOverride(other, "oversegmentation.method=pcl");
  EXPECT_EQ(Segmenter(trained_config, model).config().oversegmentation.seed_resolution_m,
            trained_config.oversegmentation.seed_resolution_m);
  try {
    Segmenter segmenter(other.segmenter, model);
    FAIL() << "expected the model to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("oversegmentation.method = pcl (--set) but forest " +
                                    forest.id() + " records oversegmentation.method = organized"));
    EXPECT_THAT(e.what(), Not(HasSubstr("unknown to this build")));
  }
}

// `config` with `key=value` given explicitly, as a settings file or --set gives it: a
// model recording another value is refused (configForModel).
SegmenterConfig givenAs(SegmenterConfig config, const std::string& key_equals_value) {
  Config c;
  c.segmenter = std::move(config);
  applyOverride(c, key_equals_value);
  return c.segmenter;
}

// The frame's features as the trainer and findmug-eval see them.
std::vector<FrameSample> extractScene(const Segmenter& segmenter, const Scene& scene,
                                      const OfflineConfig& offline = {}) {
  LabeledFrames frames{"scene", 1, [&](std::size_t) {
                         return LabeledFrame{"scene", scene.frame, scene.truth, {}};
                       }};
  ExtractionReport report;
  auto samples = extractTrainingSamples(frames, segmenter, offline, report);
  EXPECT_EQ(report.frames_used, 1);
  return samples;
}

TEST(Segmenter, RunsTheRegionAndContextRoundsOfTheModel) {
  const Scene scene = floorAndWall(true);
  SegmenterConfig config = fastConfig();
  config.regions.enabled = true;
  config.context.enabled = true;
  config.context.cross_fit_folds = 0;  // one frame: nothing to cross-fit over
  config.forest.num_trees = 4;
  config.forest.max_depth = 6;
  const auto samples = extractScene(Segmenter(config, nullptr), scene);
  ASSERT_EQ(samples.size(), 1u);
  const std::size_t n = samples[0].features.features.size();
  ASSERT_EQ(samples[0].features.regions.size(), n * kRegionFeatureDim);
  RandomForest trained = trainModel({&samples[0]}, config);
  ASSERT_NE(trained.contextRound(), nullptr);
  EXPECT_EQ(trained.dim(), kFeatureDim + kRegionFeatureDim);
  EXPECT_EQ(trained.contextRound()->featureNames(), contextRoundFeatureNames(config));
  trained.setExtractionSettings(extractionSettings(config));
  const auto model = std::make_shared<const RandomForest>(trained);

  const Segmenter segmenter(config, model);
  const LabelledFrame out = segmenter.process(scene.frame);
  ASSERT_EQ(out.features.features.size(), n);
  EXPECT_EQ(out.features.regions.size(), n * kRegionFeatureDim);
  ASSERT_EQ(out.first_round_probabilities.size(), n);
  // The daemon's path gives exactly what evaluation computes for the frame.
  const auto expected = predictSample(*model, samples[0], config);
  ASSERT_EQ(out.forest_probabilities.size(), n);
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(out.forest_probabilities[i], expected[i]) << i;
  ConfusionMatrix cm;
  cm.add(scene.truth, out.labels.labels);
  EXPECT_GT(cm.globalAccuracy(), 0.9);
}

TEST(Segmenter, RefusesModelWhoseStagesDifferFromTheConfig) {
  const Scene scene = floorAndWall(true);
  SegmenterConfig config = fastConfig();
  config.regions.enabled = true;
  config.forest.num_trees = 2;
  const auto samples = extractScene(Segmenter(config, nullptr), scene);
  const auto with_regions = std::make_shared<const RandomForest>(trainModel({&samples[0]}, config));
  EXPECT_NO_THROW(Segmenter(config, with_regions));

  SegmenterConfig no_regions = config;
  no_regions.regions.enabled = false;
  try {
    Segmenter segmenter(no_regions, with_regions);
    FAIL() << "expected the model to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("features.regions = false"));
    EXPECT_THAT(e.what(), HasSubstr("with region features"));
  }
  SegmenterConfig context = config;
  context.context.enabled = true;
  try {
    Segmenter segmenter(context, with_regions);
    FAIL() << "expected the model to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("has no auto-context round"));
    EXPECT_THAT(e.what(), HasSubstr("features.context = true"));
  }
  // A 14-column model (as every format-2 model is) with features.regions on.
  const auto plain = trainOn(Segmenter(fastConfig(), nullptr), scene);
  EXPECT_THROW(Segmenter(config, plain), Error);
  EXPECT_NO_THROW(Segmenter(fastConfig(), plain));
}

// features.scene adds its columns after the region features; the daemon's
// path (process) gives what evaluation computes, and a config giving them another
// value than the model records is refused with a message naming the setting.
TEST(Segmenter, RunsTheSceneFeaturesOfTheModel) {
  const Scene scene = floorAndWall(true);
  SegmenterConfig config = fastConfig();
  config.regions.enabled = true;
  config.scene.enabled = true;
  config.forest.num_trees = 4;
  config.forest.max_depth = 6;
  const auto samples = extractScene(Segmenter(config, nullptr), scene);
  ASSERT_EQ(samples.size(), 1u);
  const std::size_t n = samples[0].features.features.size();
  ASSERT_EQ(samples[0].features.scene.size(), n * kSceneFeatureDim);
  RandomForest trained = trainModel({&samples[0]}, config);
  EXPECT_EQ(trained.dim(), kFeatureDim + kRegionFeatureDim + kSceneFeatureDim);
  EXPECT_EQ(trained.featureNames(), firstRoundFeatureNames(config));
  EXPECT_EQ(trained.featureNames().back(), std::string(kSceneFeatureNames.back()));
  trained.setExtractionSettings(extractionSettings(config));
  const auto model = std::make_shared<const RandomForest>(trained);
  const LabelledFrame out = Segmenter(config, model).process(scene.frame);
  ASSERT_EQ(out.features.scene.size(), n * kSceneFeatureDim);
  const auto expected = predictSample(*model, samples[0], config);
  ASSERT_EQ(out.forest_probabilities.size(), n);
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(out.forest_probabilities[i], expected[i]) << i;

  SegmenterConfig not_given = config;
  not_given.scene.enabled = false;
  EXPECT_TRUE(Segmenter(not_given, model).config().scene.enabled);
  try {
    Segmenter segmenter(givenAs(config, "features.scene=false"), model);
    FAIL() << "expected the model to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("features.scene = false (--set)"));
    EXPECT_THAT(e.what(), HasSubstr("records features.scene = true"));
  }
  // A model that records no settings (as older files): the column check names every group
  // of columns it reads, the region ones too though more columns follow them.
  const auto unrecorded =
      std::make_shared<const RandomForest>(trainModel({&samples[0]}, config));
  SegmenterConfig fewer = config;
  fewer.scene.enabled = false;
  try {
    Segmenter segmenter(fewer, unrecorded);
    FAIL() << "expected the model to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("(with region features) (with scene features)"));
    EXPECT_THAT(e.what(), HasSubstr("features.scene = false"));
  }
}

// features.objects adds its columns after the scene features, computed by
// the same code in training (Segmenter::features) and in the daemon's path
// (classify): the same values to the bit and the same forest answers; a
// config giving them another value than the model records is refused naming it.
TEST(Segmenter, RunsTheObjectFeaturesOfTheModel) {
  const Scene scene = floorAndWall(true);
  SegmenterConfig config = fastConfig();
  config.regions.enabled = true;
  config.scene.enabled = true;
  config.objects.enabled = true;
  config.forest.num_trees = 4;
  config.forest.max_depth = 6;
  const auto samples = extractScene(Segmenter(config, nullptr), scene);
  ASSERT_EQ(samples.size(), 1u);
  const std::size_t n = samples[0].features.features.size();
  ASSERT_EQ(samples[0].features.objects.size(), n * kObjectFeatureDim);
  RandomForest trained = trainModel({&samples[0]}, config);
  EXPECT_EQ(trained.dim(), kFeatureDim + kRegionFeatureDim + kSceneFeatureDim + kObjectFeatureDim);
  EXPECT_EQ(trained.featureNames(), firstRoundFeatureNames(config));
  EXPECT_EQ(trained.featureNames().back(), std::string(kObjectFeatureNames[kObjectFeatureDim - 1]));
  trained.setExtractionSettings(extractionSettings(config));
  const auto model = std::make_shared<const RandomForest>(trained);
  const LabelledFrame out = Segmenter(config, model).process(scene.frame);
  ASSERT_EQ(out.features.objects.size(), n * kObjectFeatureDim);
  EXPECT_EQ(0, std::memcmp(out.features.objects.data(), samples[0].features.objects.data(),
                           n * kObjectFeatureDim * sizeof(float)));
  // The scene's floor is floor and its wall is wall, never an object.
  std::size_t floor = 0, wall = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float kind = out.features.objects[i * kObjectFeatureDim + 9];
    floor += kind == 1.0f;
    wall += kind == 2.0f;
  }
  EXPECT_GT(floor, 0u);
  EXPECT_GT(wall, 0u);
  const auto expected = predictSample(*model, samples[0], config);
  ASSERT_EQ(out.forest_probabilities.size(), n);
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(out.forest_probabilities[i], expected[i]) << i;

  try {
    Segmenter segmenter(givenAs(config, "features.objects=false"), model);
    FAIL() << "expected the model to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("features.objects = false (--set)"));
    EXPECT_THAT(e.what(), HasSubstr("records features.objects = true"));
  }
  // The context columns: a model of 3 object columns, refused by a config of all 11.
  SegmenterConfig context = config;
  context.objects.columns = ObjectColumns::Context;
  const auto context_samples = extractScene(Segmenter(context, nullptr), scene);
  ASSERT_EQ(context_samples[0].features.objects.size(), n * kObjectContextColumns.size());
  RandomForest context_model = trainModel({&context_samples[0]}, context);
  EXPECT_EQ(context_model.featureNames(), firstRoundFeatureNames(context));
  EXPECT_EQ(context_model.featureNames().back(), "patch_height_in_object");
  context_model.setExtractionSettings(extractionSettings(context));
  const auto context_shared = std::make_shared<const RandomForest>(context_model);
  EXPECT_NO_THROW(Segmenter(context, context_shared).process(scene.frame));
  EXPECT_EQ(Segmenter(config, context_shared).config().objects.columns, ObjectColumns::Context);
  try {
    Segmenter segmenter(givenAs(config, "features.objects_columns=all"), context_shared);
    FAIL() << "expected the context-column model to be refused by an all-column config";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("records features.objects_columns = context"));
  }
  // The relations columns: trained and run through the same rows, refused by a context config.
  SegmenterConfig relations = config;
  relations.objects.columns = ObjectColumns::Relations;
  const auto relations_samples = extractScene(Segmenter(relations, nullptr), scene);
  ASSERT_EQ(relations_samples[0].features.objects.size(), n * kObjectRelationsColumns.size());
  RandomForest relations_model = trainModel({&relations_samples[0]}, relations);
  EXPECT_EQ(relations_model.featureNames().back(), "object_load_on_top");
  relations_model.setExtractionSettings(extractionSettings(relations));
  const auto relations_shared = std::make_shared<const RandomForest>(relations_model);
  EXPECT_EQ(Segmenter(relations, relations_shared).process(scene.frame).features.objects,
            relations_samples[0].features.objects);
  EXPECT_THROW(Segmenter(givenAs(context, "features.objects_columns=context"), relations_shared),
               Error);
  // Objects on and regions off: the regions are still formed for the objects.
  SegmenterConfig objects_only = config;
  objects_only.regions.enabled = false;
  const auto only = extractScene(Segmenter(objects_only, nullptr), scene);
  ASSERT_EQ(only.size(), 1u);
  EXPECT_TRUE(only[0].features.regions.empty());
  EXPECT_EQ(only[0].features.objects, samples[0].features.objects);
}

// training.extra_oversegmentations: each frame gets training-only views
// through other seed resolutions, whose patches join the training set;
// training.sample_weight=pixels weighs each patch by its pixel count.
TEST(Segmenter, TrainingAugmentationAndSampleWeights) {
  const Scene scene = floorAndWall(true);
  OfflineConfig offline;
  offline.training.extra_oversegmentations = 2;
  offline.training.extra_seed_scale = 0.7f;
  const auto samples = extractScene(Segmenter(fastConfig(), nullptr), scene, offline);
  ASSERT_EQ(samples.size(), 1u);
  ASSERT_EQ(samples[0].variants.size(), 2u);
  const std::size_t own = samples[0].segment_labels.size();
  // Seed resolution x0.7 gives more patches, x1/0.7 fewer.
  EXPECT_GT(samples[0].variants[0].segment_labels.size(), own);
  EXPECT_LT(samples[0].variants[1].segment_labels.size(), own);
  std::size_t labelled = 0;
  for (const FrameSample* s : {&samples[0], &samples[0].variants[0], &samples[0].variants[1]})
    for (auto y : s->segment_labels) labelled += y < kNumLabels;
  const TrainingSet patches = makeTrainingSet({&samples[0]});
  EXPECT_EQ(patches.labels.size(), labelled);
  EXPECT_TRUE(patches.weights.empty());

  const auto plain = extractScene(Segmenter(fastConfig(), nullptr), scene);
  EXPECT_TRUE(plain[0].variants.empty());
  const TrainingSet pixels = makeTrainingSet({&plain[0]}, SampleWeighting::Pixels);
  ASSERT_EQ(pixels.weights.size(), pixels.labels.size());
  std::size_t row = 0;
  for (std::size_t k = 0; k < plain[0].segment_labels.size(); ++k) {
    if (plain[0].segment_labels[k] >= kNumLabels) continue;
    EXPECT_EQ(pixels.weights[row++], static_cast<float>(plain[0].segment_pixels[k]));
  }
  const TrainingSet roots = makeTrainingSet({&plain[0]}, SampleWeighting::SqrtPixels);
  ASSERT_EQ(roots.weights.size(), pixels.weights.size());
  for (std::size_t i = 0; i < roots.weights.size(); ++i)
    EXPECT_FLOAT_EQ(roots.weights[i] * roots.weights[i], pixels.weights[i]);
}

// training.split_labels = nyu40: each patch carries the plurality NYU-40
// class of its pixels of the patch's own label, and the training set hands
// them to the forest as split labels; a frame without them is refused.
TEST(Segmenter, SplitLabelsFromTheFineLabelsOfEachPatch) {
  const Scene scene = floorAndWall(true);
  const int w = scene.frame.width;
  LabeledFrame labelled{"scene", scene.frame, scene.truth, {}};
  labelled.fine_labels.assign(scene.truth.size(), 0);
  for (std::size_t p = 0; p < scene.truth.size(); ++p) {
    const int x = static_cast<int>(p % static_cast<std::size_t>(w));
    if (scene.truth[p] == static_cast<std::uint8_t>(Label::Floor)) labelled.fine_labels[p] = 2;
    // The wall is two kinds: "wall" on the left, "door" on the right.
    if (scene.truth[p] == static_cast<std::uint8_t>(Label::Wall))
      labelled.fine_labels[p] = x < w / 2 ? 1 : 8;
  }
  LabeledFrames frames{"scene", 1, [&](std::size_t) { return labelled; }};
  ExtractionReport report;
  const auto samples = extractSamples(frames, Segmenter(fastConfig(), nullptr), report);
  ASSERT_EQ(samples.size(), 1u);
  const FrameSample& s = samples[0];
  ASSERT_EQ(s.segment_fine_labels.size(), s.segment_labels.size());
  // Brute force: the plurality fine class per segment among its pixels of its label.
  std::vector<std::array<int, kNyu40Classes + 1>> votes(s.segment_labels.size());
  for (std::size_t p = 0; p < s.pixel_segment.size(); ++p) {
    const int k = s.pixel_segment[p];
    if (k < 0 || scene.truth[p] != s.segment_labels[static_cast<std::size_t>(k)]) continue;
    ++votes[static_cast<std::size_t>(k)][labelled.fine_labels[p]];
  }
  std::set<int> kinds;
  for (std::size_t k = 0; k < s.segment_labels.size(); ++k) {
    if (s.segment_labels[k] >= kNumLabels) {
      EXPECT_EQ(s.segment_fine_labels[k], 0);
      continue;
    }
    const auto& v = votes[k];
    EXPECT_EQ(v[s.segment_fine_labels[k]], *std::max_element(v.begin() + 1, v.end())) << k;
    kinds.insert(s.segment_fine_labels[k]);
  }
  EXPECT_EQ(kinds, (std::set<int>{1, 2, 8}));

  const TrainingSet set = makeTrainingSet({&s}, SampleWeighting::Patches, SplitLabels::Nyu40);
  EXPECT_EQ(set.split_classes, kNyu40Classes + 1);
  ASSERT_EQ(set.split_labels.size(), set.labels.size());
  std::size_t row = 0;
  for (std::size_t k = 0; k < s.segment_labels.size(); ++k) {
    if (s.segment_labels[k] < kNumLabels) {
      EXPECT_EQ(set.split_labels[row++], s.segment_fine_labels[k]);
    }
  }
  EXPECT_TRUE(makeTrainingSet({&s}).split_labels.empty());  // the default splits on labels
  EXPECT_EQ(makeTrainingSet({&s}, SampleWeighting::Patches, SplitLabels::Nyu13).split_classes,
            kNyu13Classes + 1);
  FrameSample beyond = s;  // an NYU-40 id read as NYU-13 is refused
  for (std::size_t k = 0; k < beyond.segment_labels.size(); ++k)
    if (beyond.segment_labels[k] < kNumLabels) beyond.segment_fine_labels[k] = 20;
  try {
    makeTrainingSet({&beyond}, SampleWeighting::Patches, SplitLabels::Nyu13);
    FAIL() << "expected id 20 to be refused as an NYU-13 class";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("has no NYU-13 class (id 20)"));
  }

  const SegmenterConfig config = fastConfig();
  TrainingOptions split40;
  split40.split_labels = SplitLabels::Nyu40;
  EXPECT_FALSE(trainModel({&s}, config, split40).empty());
  const auto without = extractScene(Segmenter(fastConfig(), nullptr), scene);
  try {
    trainModel({&without[0]}, config, split40);
    FAIL() << "expected a frame without NYU-40 labels to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("frame scene has no NYU-40 labels (a dataset folder needs label40/)"));
  }

  // Internal classes (learner.classes) take a frame labelled with the 8 labels
  // only beside finely labelled ones (a robot owner's frames from the Label
  // page): its patches' fine classes are inferred, so both wall kinds remain.
  SegmenterConfig internal = fastConfig();
  internal.learner.classes = ClassScheme::Nyu40;
  const RandomForest mixed = trainModel({&s, &without[0]}, internal);
  std::set<std::string> names(mixed.internalClasses().names.begin(),
                              mixed.internalClasses().names.end());
  EXPECT_EQ(names, (std::set<std::string>{"floor/floor", "wall/door", "wall/wall"}));
  // With no finely labelled frame at all there is nothing to infer from.
  try {
    trainModel({&without[0]}, internal);
    FAIL() << "expected a training without any fine labels to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("need frames with finer labels of the same label"));
  }
}

TEST(Segmenter, MajorityLabelsPerSegment) {
  Oversegmentation seg;
  seg.width = 4;
  seg.height = 1;
  seg.segments = {{0, 1, 2}, {3}};
  seg.pixel_segment = {0, 0, 0, 1};
  const std::vector<std::uint8_t> truth = {2, 2, 1, kVoidLabel};
  const auto labels = segmentMajorityLabels(seg, truth);
  ASSERT_EQ(labels.size(), 2u);
  EXPECT_EQ(labels[0], 2);
  EXPECT_EQ(labels[1], kVoidLabel);
  EXPECT_THROW(segmentMajorityLabels(seg, {1, 2}), Error);
}

}  // namespace
}  // namespace findmug
