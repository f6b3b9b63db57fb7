// Semi-supervised rounds (pseudo_labels.hpp) on real NYU frames: labelled
// frames from nyuv2_labeled, unlabelled ones from nyuv2_unlabeled_train with
// their NYU gravity. Pseudo-labelled patches come only from confident
// patches, carry the Segmenter's label and the pseudo weight, respect the
// per-label cap; a threshold nothing passes leaves the model as it was; a
// round that adds patches changes it.
#include <gtest/gtest.h>

#include <algorithm>

#include "findmug/settings/config.hpp"
#include "findmug/common/error.hpp"
#include "findmug/offline/pseudo_labels.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

struct Frames {
  std::vector<FrameSample> labelled, unlabelled;
  std::vector<const FrameSample*> labelledPointers() const {
    std::vector<const FrameSample*> out;
    for (const auto& s : labelled) out.push_back(&s);
    return out;
  }
};

SegmenterConfig smallConfig() {
  SegmenterConfig config;
  config.oversegmentation.kind = OversegmenterKind::Organized;
  config.ground.source = GroundSource::Gravity;
  config.regions.enabled = true;  // and so the table region vote, as shipped
  config.forest.num_trees = 4;
  config.forest.num_threads = 1;
  return config;
}

// Four labelled frames and three unlabelled ones, extracted once.
const Frames& frames(const SegmenterConfig& config, const std::filesystem::path& labelled_dir,
                     const std::filesystem::path& unlabelled_dir,
                     const std::filesystem::path& rotations) {
  static const Frames out = [&] {
    Frames f;
    DatasetOptions options;
    options.nyu_rotations_file = rotations.string();
    options.fine_labels_folder = "label13";
    const DatasetFolder labelled(labelled_dir.string(), options);
    LabeledFrames some = framesOf(labelled);
    some.count = 4;
    ExtractionReport report;
    f.labelled = extractSamples(some, Segmenter(config, nullptr), report);
    DatasetOptions unlabelled_options;
    unlabelled_options.nyu_rotations_file = rotations.string();
    unlabelled_options.require_labels = false;
    const DatasetFolder unlabelled(unlabelled_dir.string(), unlabelled_options);
    LabeledFrames few = framesOf(unlabelled);
    few.count = 3;
    f.unlabelled = extractSamples(few, Segmenter(unlabelledExtractionConfig(config), nullptr),
                                  report);
    return f;
  }();
  return out;
}

#define PSEUDO_FRAMES(config, f)                                                       \
  FINDMUG_REQUIRE_DATA(labelled_dir_, "nyuv2_labeled");                                \
  FINDMUG_REQUIRE_DATA(unlabelled_dir_, "nyuv2_unlabeled_train");                      \
  FINDMUG_REQUIRE_DATA(rotations_, "nyuv2_meta/camera_rotations_NYU.txt");             \
  const Frames& f = frames(config, labelled_dir_, unlabelled_dir_, rotations_);        \
  ASSERT_EQ(f.labelled.size(), 4u);                                                    \
  ASSERT_EQ(f.unlabelled.size(), 3u);                                                  \
  for (const FrameSample& u : f.unlabelled)                                            \
    ASSERT_TRUE(std::all_of(u.segment_labels.begin(), u.segment_labels.end(),          \
                            [](std::uint8_t l) { return l == kVoidLabel; }))           \
        << u.name << " came with labels"

std::vector<SampleLabelling> labelAll(const RandomForest& model, const Frames& f,
                                      const SegmenterConfig& config) {
  std::vector<SampleLabelling> out;
  for (const FrameSample& u : f.unlabelled) {
    const RegionFeatures regions = sampleRegionFeatures(u, config.regions);
    out.push_back(labelSample(model, u, config, &regions));
  }
  return out;
}

// Every kept patch passed the threshold and carries the label the Segmenter
// gave it; with no cap every confident patch is kept.
TEST(PseudoLabels, OnlyConfidentPatchesBecomeTrainingPatchesWithThePipelinesLabel) {
  SegmenterConfig config = smallConfig();
  TrainingOptions training;
  PSEUDO_FRAMES(config, f);
  const RandomForest model = trainModel(f.labelledPointers(), config);
  const std::vector<SampleLabelling> labellings = labelAll(model, f, config);
  training.pseudo_min_confidence = 0.6f;
  training.pseudo_weight = 0.5f;
  training.pseudo_class_cap = 1000.0f;
  PseudoLabelRound round;
  const std::vector<FrameSample> pseudo = pseudoLabelledSamples(
      f.unlabelled, labellings, f.labelledPointers(), config, training, round);
  int kept = 0, below = 0;
  for (const FrameSample& p : pseudo) {
    const auto it = std::find_if(f.unlabelled.begin(), f.unlabelled.end(),
                                 [&](const FrameSample& u) { return u.name + "~pseudo" == p.name; });
    ASSERT_NE(it, f.unlabelled.end()) << p.name;
    const MrfResult& m = labellings[static_cast<std::size_t>(it - f.unlabelled.begin())].mrf;
    EXPECT_EQ(p.training_weight, 0.5f);
    for (std::size_t k = 0; k < p.segment_labels.size(); ++k) {
      if (p.segment_labels[k] == kVoidLabel) {
        below += m.confidence[k] <= 0.6f;
        continue;
      }
      ++kept;
      EXPECT_GT(m.confidence[k], 0.6f) << p.name << " segment " << k;
      EXPECT_EQ(p.segment_labels[k], m.labels[k]) << p.name << " segment " << k;
    }
  }
  int confident = 0;
  for (const auto& l : labellings)
    for (const float c : l.mrf.confidence) confident += c > 0.6f;
  EXPECT_GT(kept, 0);
  EXPECT_GT(below, 0);  // the threshold did leave patches out
  EXPECT_EQ(kept, confident);
  EXPECT_EQ(kept, round.keptTotal());

  // The per-label cap: at most cap x the labelled frames' patches of a label.
  training.pseudo_class_cap = 0.05f;
  PseudoLabelRound capped;
  pseudoLabelledSamples(f.unlabelled, labellings, f.labelledPointers(), config, training, capped);
  std::array<long, kNumLabels> labelled_count{};
  for (const FrameSample& s : f.labelled)
    for (const std::uint8_t l : s.segment_labels)
      if (l < kNumLabels) ++labelled_count[l];
  for (int c = 0; c < kNumLabels; ++c) {
    EXPECT_LE(capped.kept[static_cast<std::size_t>(c)],
              static_cast<int>(0.05 * static_cast<double>(labelled_count[static_cast<std::size_t>(c)])))
        << kLabelNames[static_cast<std::size_t>(c)];
    EXPECT_LE(capped.kept[static_cast<std::size_t>(c)], round.kept[static_cast<std::size_t>(c)]);
  }
  EXPECT_LT(capped.keptTotal(), round.keptTotal());
}

// Threshold 1.0: no patch passes (confidence is at most 1), nothing is
// added, and the model is the one trained on the labelled frames alone.
TEST(PseudoLabels, ThresholdOneAddsNothingAndLeavesTheModelAsItWas) {
  SegmenterConfig config = smallConfig();
  TrainingOptions training;
  PSEUDO_FRAMES(config, f);
  const RandomForest plain = trainModel(f.labelledPointers(), config);
  training.pseudo_rounds = 2;
  training.pseudo_min_confidence = 1.0f;
  PseudoLabelReport report;
  const RandomForest model = trainModelWithPseudoLabels(f.labelledPointers(), f.unlabelled, config,
                                                        training, &report);
  ASSERT_EQ(report.rounds.size(), 2u);
  for (const auto& r : report.rounds) {
    EXPECT_EQ(r.keptTotal(), 0);
    EXPECT_TRUE(r.frames.empty());
  }
  EXPECT_EQ(report.pool.size(), 3u);
  EXPECT_EQ(model.id(), plain.id());
}

// A round that keeps patches retrains on them: the model changes, and the
// rounds are reported with the frames the patches came from. With internal
// classes each pseudo patch gets a fine class of its own label.
TEST(PseudoLabels, ARoundChangesTheModel) {
  SegmenterConfig config = smallConfig();
  TrainingOptions training;
  PSEUDO_FRAMES(config, f);
  config.learner.classes = ClassScheme::Nyu13;
  const RandomForest plain = trainModel(f.labelledPointers(), config);
  training.pseudo_rounds = 1;
  training.pseudo_min_confidence = 0.5f;
  PseudoLabelReport report;
  std::vector<std::string> ids;
  const RandomForest model = trainModelWithPseudoLabels(
      f.labelledPointers(), f.unlabelled, config, training, &report,
      [&](int, const RandomForest& m) { ids.push_back(m.id()); });
  ASSERT_EQ(report.rounds.size(), 1u);
  EXPECT_GT(report.rounds[0].keptTotal(), 0);
  EXPECT_FALSE(report.rounds[0].frames.empty());
  ASSERT_EQ(ids.size(), 2u);
  EXPECT_EQ(ids[0], plain.id());
  EXPECT_EQ(ids[1], model.id());
  EXPECT_NE(model.id(), plain.id());
  EXPECT_EQ(model.internalClasses().scheme, "nyu13");

  const std::vector<SampleLabelling> labellings = labelAll(plain, f, config);
  PseudoLabelRound round;
  for (const FrameSample& p : pseudoLabelledSamples(f.unlabelled, labellings, f.labelledPointers(),
                                                    config, training, round)) {
    ASSERT_EQ(p.segment_fine_labels.size(), p.segment_labels.size());
    for (std::size_t k = 0; k < p.segment_labels.size(); ++k)
      EXPECT_EQ(p.segment_fine_labels[k] != 0, p.segment_labels[k] != kVoidLabel) << k;
  }
}

// The settings: named, range-checked, defaults off.
TEST(PseudoLabels, SettingsAreNamedAndRangeChecked) {
  Config c;
  EXPECT_EQ(c.offline.training.pseudo_rounds, 0);
  applyOverride(c, "training.pseudo_rounds=2");
  applyOverride(c, "training.pseudo_min_confidence=0.7");
  applyOverride(c, "training.pseudo_weight=0.5");
  applyOverride(c, "training.pseudo_class_cap=0.25");
  EXPECT_EQ(c.offline.training.pseudo_rounds, 2);
  EXPECT_FLOAT_EQ(c.offline.training.pseudo_min_confidence, 0.7f);
  EXPECT_FLOAT_EQ(c.offline.training.pseudo_weight, 0.5f);
  EXPECT_FLOAT_EQ(c.offline.training.pseudo_class_cap, 0.25f);
  for (const char* bad : {"training.pseudo_rounds=-1", "training.pseudo_min_confidence=1.5",
                          "training.pseudo_weight=0", "training.pseudo_weight=2",
                          "training.pseudo_class_cap=-1"}) {
    try {
      applyOverride(c, bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const Error& e) {
      const std::string key = std::string(bad).substr(0, std::string(bad).find('='));
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace findmug
