// Tests of the learners behind the model file (learner.kind, learner.classes):
// models on internal classes (NYU-13 / NYU-40 pairs) merged into the 8 labels,
// gradient-boosted trees (XGBoost) next to the forest, format 4 round trips,
// format 3 still loading, corrupt or mismatched models refused by name.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <random>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "learner/forest_format.hpp"    // internal: file layout and checksum (src/)
#include "test_data.hpp"
#include "file_bytes.hpp"
#include "model_bytes.hpp"
#include "learner/xgboost_learner.hpp"  // internal: the booster's stored bytes (src/)

namespace findmug {
namespace {

using ::testing::HasSubstr;
using test::TempDir;

// `per_label` Gaussian blobs per label in 14-D, each blob its own internal
// class: internal class c belongs to label c % 8. Returns the set with
// split_labels = internal classes (weighted by them) and the class map.
struct FineSet {
  TrainingSet set;
  InternalClasses classes;
};

FineSet makeFineBlobs(int per_label, int per_class, std::uint32_t seed, const std::string& scheme) {
  const int k = per_label * kNumLabels;
  std::mt19937 mean_rng(4321);
  std::uniform_real_distribution<float> mean_dist(0.0f, 10.0f);
  std::vector<FeatureVector> means(static_cast<std::size_t>(k));
  for (auto& m : means)
    for (float& v : m) v = mean_dist(mean_rng);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 0.7f);
  FineSet out;
  out.classes.scheme = scheme;
  for (int c = 0; c < k; ++c) {
    out.classes.names.push_back(std::string(kLabelNames[c % kNumLabels]) + "/fine" +
                                std::to_string(c));
    out.classes.to_label.push_back(static_cast<std::uint8_t>(c % kNumLabels));
  }
  for (int i = 0; i < per_class; ++i) {
    for (int c = 0; c < k; ++c) {
      FeatureVector x;
      for (int f = 0; f < kFeatureDim; ++f) x[f] = means[static_cast<std::size_t>(c)][f] + noise(rng);
      out.set.features.push_back(x);
      out.set.labels.push_back(static_cast<std::uint8_t>(c % kNumLabels));
      out.set.split_labels.push_back(static_cast<std::uint8_t>(c));
    }
  }
  out.set.split_classes = k;
  out.set.weight_by_split_labels = true;
  return out;
}

TrainingSet labelsOnly(TrainingSet set) {
  set.split_labels.clear();
  set.split_classes = 0;
  set.weight_by_split_labels = false;
  return set;
}

using test::readBytes;
using test::fixChecksum;
using test::putU32;
using test::putU64;
using test::writeBytes;


// Predictions of two models on the same rows are the same bits.
void expectSamePredictions(const RandomForest& a, const RandomForest& b,
                           const std::vector<FeatureVector>& rows) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const ClassProbabilities pa = a.predict(rows[i]);
    const ClassProbabilities pb = b.predict(rows[i]);
    ASSERT_EQ(std::memcmp(pa.data(), pb.data(), sizeof pa), 0) << "row " << i;
  }
}

double accuracy(const RandomForest& model, const TrainingSet& set) {
  int correct = 0;
  for (std::size_t i = 0; i < set.features.size(); ++i) {
    const auto p = model.predict(set.features[i]);
    correct += std::max_element(p.begin(), p.end()) - p.begin() == set.labels[i];
  }
  return static_cast<double>(correct) / static_cast<double>(set.features.size());
}

XGBoostParams smallBooster() {
  XGBoostParams p;
  p.rounds = 8;
  p.max_depth = 3;
  p.seed = 7;
  return p;
}

// ---------------------------------------------------------------------------
// Internal classes with the forest

TEST(LearnerForest, ThirteenAndFortyInternalClassesRoundTripAndPredictTheSame) {
  TempDir dir;
  // 2 x 8 = 16 internal classes ("nyu13"-sized) and 5 x 8 = 40 ("nyu40"-sized).
  for (const auto& [per_label, scheme] : {std::pair{2, "nyu13"}, std::pair{5, "nyu40"}}) {
    SCOPED_TRACE(scheme);
    const FineSet fine = makeFineBlobs(per_label, 20, 1, scheme);
    ForestParams params;
    params.num_trees = 4;
    params.seed = 3;
    RandomForest forest = RandomForest::train(fine.set, params);
    forest.setInternalClasses(fine.classes);
    EXPECT_EQ(forest.internalClasses().count(), per_label * kNumLabels);
    EXPECT_GT(accuracy(forest, makeFineBlobs(per_label, 5, 2, scheme).set), 0.9);
    const std::string path = dir.str(std::string(scheme) + ".fmf");
    forest.save(path);
    const RandomForest loaded = RandomForest::load(path);
    EXPECT_EQ(loaded.formatVersion(), 5u);
    EXPECT_EQ(loaded.learnerKind(), LearnerKind::Forest);
    EXPECT_EQ(loaded.internalClasses(), fine.classes);
    EXPECT_EQ(loaded.id(), forest.id());
    EXPECT_EQ(loaded.summary(), "forest of 4 trees, " + std::to_string(per_label * kNumLabels) +
                                    " internal classes (" + scheme + ")");
    expectSamePredictions(forest, loaded, makeFineBlobs(per_label, 3, 9, scheme).set.features);
  }
}

// Merging leaves into labels equals merging the averaged fine posterior, but
// weighting by fine class frequency is not weighting by label frequency: a
// single leaf over label A (fine a1: 90 samples, a2: 10) and B (50) holds
// A:B = 1:1 with label weights (75 each) and 2:1 with fine weights (50 each).
TEST(LearnerForest, ClassWeightingByInternalClassesDiffersFromLabels) {
  TrainingSet set;
  auto add = [&](int n, std::uint8_t label, std::uint8_t fine, float x) {
    for (int i = 0; i < n; ++i) {
      FeatureVector v{};
      v[0] = x + 0.01f * static_cast<float>(i);
      set.features.push_back(v);
      set.labels.push_back(label);
      set.split_labels.push_back(fine);
    }
  };
  add(90, 1, 0, 0.0f);
  add(10, 1, 1, 5.0f);
  add(50, 2, 2, 10.0f);
  set.split_classes = 3;
  ForestParams params;
  params.num_trees = 1;
  params.max_depth = 0;  // one leaf: the weighted class histogram
  set.weight_by_split_labels = true;
  const auto fine = RandomForest::train(set, params).predict(FeatureVector{});
  EXPECT_NEAR(fine[1], 2.0 / 3.0, 1e-6);
  EXPECT_NEAR(fine[2], 1.0 / 3.0, 1e-6);
  set.weight_by_split_labels = false;
  const auto coarse = RandomForest::train(set, params).predict(FeatureVector{});
  EXPECT_NEAR(coarse[1], 0.5, 1e-6);
  EXPECT_NEAR(coarse[2], 0.5, 1e-6);
}

TEST(LearnerForest, BadClassMapsAreRefused) {
  RandomForest forest = RandomForest::train(labelsOnly(makeFineBlobs(1, 5, 1, "nyu13").set), {});
  auto refused = [&](InternalClasses classes, const std::string& word) {
    try {
      forest.setInternalClasses(std::move(classes));
      ADD_FAILURE() << "accepted a bad class map; expected '" << word << "'";
    } catch (const Error& e) {
      EXPECT_THAT(e.what(), HasSubstr("bad class map"));
      EXPECT_THAT(e.what(), HasSubstr(word));
    }
  };
  InternalClasses good = makeFineBlobs(2, 1, 1, "nyu13").classes;
  EXPECT_NO_THROW(forest.setInternalClasses(good));
  auto bad = good;
  bad.to_label[3] = 8;
  refused(bad, "merges into label 8");
  bad = good;
  bad.to_label.pop_back();
  refused(bad, "class count mismatch");
  bad = good;
  bad.names[2] = bad.names[1];
  refused(bad, "appears twice");
  bad = good;
  bad.scheme = "nyu894";
  refused(bad, "unknown scheme");
  bad = labelClasses();
  std::swap(bad.names[0], bad.names[1]);
  refused(bad, "labels in order");
}

// ---------------------------------------------------------------------------
// Gradient-boosted trees

TEST(LearnerXGBoost, LearnsAndRoundTripsBitIdentically) {
  TempDir dir;
  const FineSet train = makeFineBlobs(1, 40, 1, "labels");
  const RandomForest model = RandomForest::trainBoosted(labelsOnly(train.set), labelClasses(),
                                                        smallBooster(), true, 1);
  EXPECT_EQ(model.learnerKind(), LearnerKind::XGBoost);
  EXPECT_FALSE(model.empty());
  EXPECT_TRUE(model.trees().empty());
  const TrainingSet probe = makeFineBlobs(1, 10, 5, "labels").set;
  EXPECT_GT(accuracy(model, probe), 0.9);
  // One call for many rows gives what the rows one by one give.
  std::vector<float> rows;
  for (const auto& x : probe.features) rows.insert(rows.end(), x.begin(), x.end());
  std::vector<ClassProbabilities> batch(probe.features.size());
  model.predictRows(rows, probe.features.size(), batch);
  for (std::size_t i = 0; i < batch.size(); ++i) {
    const auto one = model.predict(probe.features[i]);
    ASSERT_EQ(std::memcmp(one.data(), batch[i].data(), sizeof one), 0) << i;
    double sum = 0.0;
    for (float p : one) sum += p;
    EXPECT_NEAR(sum, 1.0, 1e-5);
  }
  const std::string path = dir.str("boosted.fmf");
  model.save(path);
  const RandomForest loaded = RandomForest::load(path);
  EXPECT_EQ(loaded.learnerKind(), LearnerKind::XGBoost);
  EXPECT_EQ(loaded.formatVersion(), 5u);
  EXPECT_EQ(loaded.id(), model.id());
  EXPECT_EQ(loaded.xgboostParams().rounds, 8);
  EXPECT_EQ(loaded.xgboostParams().max_depth, 3);
  EXPECT_EQ(loaded.xgboostParams().seed, 7);
  EXPECT_EQ(loaded.summary(), "xgboost of 8 rounds, 8 classes (labels)");
  expectSamePredictions(model, loaded, probe.features);
  // Saving the loaded model gives the same bytes.
  loaded.save(dir.str("again.fmf"));
  EXPECT_EQ(readBytes(dir.str("again.fmf")), readBytes(path));
  // The same seed trains the same booster.
  const RandomForest twin = RandomForest::trainBoosted(labelsOnly(train.set), labelClasses(),
                                                       smallBooster(), true, 1);
  EXPECT_EQ(twin.id(), model.id());
}

TEST(LearnerXGBoost, InternalClassesMergeIntoLabelsAndRoundTrip) {
  TempDir dir;
  const FineSet train = makeFineBlobs(2, 30, 1, "nyu13");
  const RandomForest model =
      RandomForest::trainBoosted(train.set, train.classes, smallBooster(), true, 1);
  EXPECT_EQ(model.internalClasses(), train.classes);
  const TrainingSet probe = makeFineBlobs(2, 5, 8, "nyu13").set;
  EXPECT_GT(accuracy(model, probe), 0.9);
  // The 8 label probabilities are the 16 class probabilities merged: they sum to 1.
  for (const auto& x : probe.features) {
    const auto p = model.predict(x);
    double sum = 0.0;
    for (float v : p) sum += v;
    EXPECT_NEAR(sum, 1.0, 1e-5);
  }
  model.save(dir.str("fine.fmf"));
  const RandomForest loaded = RandomForest::load(dir.str("fine.fmf"));
  EXPECT_EQ(loaded.internalClasses(), train.classes);
  expectSamePredictions(model, loaded, probe.features);
}

// Class weighting balances the internal classes or the labels: on a set whose
// internal classes differ in size the two give different boosters.
TEST(LearnerXGBoost, ClassWeightingByInternalClassesOrLabels) {
  FineSet fine = makeFineBlobs(2, 12, 1, "nyu13");
  TrainingSet& set = fine.set;
  // Keep a third of internal class 0's samples (label 0 keeps all of class 8's).
  TrainingSet uneven = set;
  uneven.features.clear();
  uneven.labels.clear();
  uneven.split_labels.clear();
  int seen = 0;
  for (std::size_t i = 0; i < set.features.size(); ++i) {
    if (set.split_labels[i] == 0 && seen++ % 3 != 0) continue;
    uneven.features.push_back(set.features[i]);
    uneven.labels.push_back(set.labels[i]);
    uneven.split_labels.push_back(set.split_labels[i]);
  }
  uneven.weight_by_split_labels = true;
  const auto by_classes =
      RandomForest::trainBoosted(uneven, fine.classes, smallBooster(), true, 1);
  uneven.weight_by_split_labels = false;
  const auto by_labels = RandomForest::trainBoosted(uneven, fine.classes, smallBooster(), true, 1);
  EXPECT_NE(by_classes.id(), by_labels.id());
  // Without class weighting the flag changes nothing.
  const auto plain_a = RandomForest::trainBoosted(uneven, fine.classes, smallBooster(), false, 1);
  uneven.weight_by_split_labels = true;
  const auto plain_b = RandomForest::trainBoosted(uneven, fine.classes, smallBooster(), false, 1);
  EXPECT_EQ(plain_a.id(), plain_b.id());
}

TEST(LearnerXGBoost, RefusesBadParameters) {
  const TrainingSet set = labelsOnly(makeFineBlobs(1, 5, 1, "labels").set);
  XGBoostParams p = smallBooster();
  p.eta = 0.0;
  EXPECT_THAT([&] { RandomForest::trainBoosted(set, labelClasses(), p, true, 1); },
              ::testing::ThrowsMessage<Error>(HasSubstr("eta")));
  p = smallBooster();
  p.rounds = 0;
  EXPECT_THAT([&] { RandomForest::trainBoosted(set, labelClasses(), p, true, 1); },
              ::testing::ThrowsMessage<Error>(HasSubstr("rounds")));
}

// ---------------------------------------------------------------------------
// The model file: format 3 still loads, corrupt boosted files are refused

// The fixture is the daemon's default model before issue 35 (models/findmug.fmf
// 35d9fa37 at commit 6f38cdc, format 3; tests/fixtures/models/README.md): a model a
// robot may still have installed.
TEST(LearnerFile, ShippedFormat3ModelStillLoads) {
  const auto path =
      (test::sourceDir() / "tests" / "fixtures" / "models" / "findmug-35d9fa37-format3.fmf")
          .string();
  const RandomForest model = RandomForest::load(path);
  EXPECT_EQ(model.formatVersion(), 3u);
  EXPECT_EQ(model.learnerKind(), LearnerKind::Forest);
  EXPECT_EQ(model.internalClasses(), labelClasses());
  EXPECT_FALSE(model.trees().empty());
  EXPECT_EQ(model.pairwiseContext(), nullptr);
  // Written again, it becomes format 5 (without a pairwise term) and predicts the same.
  TempDir dir;
  model.save(dir.str("v5.fmf"));
  const RandomForest again = RandomForest::load(dir.str("v5.fmf"));
  EXPECT_EQ(again.formatVersion(), 5u);
  EXPECT_EQ(again.pairwiseContext(), nullptr);
  std::vector<float> row(static_cast<std::size_t>(model.dim()), 0.5f);
  const auto a = model.predict(row);
  const auto b = again.predict(row);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof a), 0);
}

class BoostedFileCorruption : public ::testing::Test {
 protected:
  void SetUp() override {
    const FineSet train = makeFineBlobs(2, 10, 1, "nyu13");
    model_ = RandomForest::trainBoosted(train.set, train.classes, smallBooster(), true, 1);
    path_ = dir_.str("boosted.fmf");
    model_.save(path_);
    good_ = readBytes(path_);
    blob_size_ = model_.booster()->blob.size();
    // Layout tail: uint64 blob length, blob, uint8 context flag, uint8 pairwise term
    // flag, uint64 checksum.
    blob_offset_ = good_.size() - 8 - 1 - 1 - blob_size_;
    length_offset_ = blob_offset_ - 8;
    std::uint64_t stored = 0;
    for (int i = 0; i < 8; ++i)
      stored |= static_cast<std::uint64_t>(good_[length_offset_ + i]) << (8 * i);
    ASSERT_EQ(stored, blob_size_);
  }

  void expectRefused(const std::vector<std::uint8_t>& bytes, const std::string& word) {
    test::expectModelRefused(dir_.str("bad.fmf"), bytes, word);
  }

  // Offset of internal class `c`'s label byte (after its name).
  std::size_t classLabelOffset(int c) const {
    const std::string& name = model_.internalClasses().names[static_cast<std::size_t>(c)];
    const auto it = std::search(good_.begin(), good_.end(), name.begin(), name.end());
    return static_cast<std::size_t>(it - good_.begin()) + name.size();
  }

  TempDir dir_;
  RandomForest model_;
  std::string path_;
  std::vector<std::uint8_t> good_;
  std::size_t blob_size_ = 0, blob_offset_ = 0, length_offset_ = 0;
};

TEST_F(BoostedFileCorruption, IntactFileLoads) {
  EXPECT_EQ(RandomForest::load(path_).id(), model_.id());
}

TEST_F(BoostedFileCorruption, TruncatedBoosterBlob) {
  // The file ends inside the blob.
  auto bytes = std::vector<std::uint8_t>(good_.begin(),
                                         good_.begin() + static_cast<std::ptrdiff_t>(blob_offset_ + blob_size_ / 2));
  expectRefused(bytes, "booster blob truncated");
  // Length and bytes agree and the checksum is right, but the blob is cut short.
  bytes = good_;
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(blob_offset_ + blob_size_ / 2),
              bytes.begin() + static_cast<std::ptrdiff_t>(blob_offset_ + blob_size_));
  putU64(bytes, length_offset_, blob_size_ - blob_size_ / 2);
  fixChecksum(bytes);
  expectRefused(bytes, "booster blob truncated or corrupt");
}

TEST_F(BoostedFileCorruption, WrongChecksum) {
  auto bytes = good_;
  bytes[blob_offset_ + blob_size_ / 3] ^= 0x01;
  expectRefused(bytes, "checksum mismatch");
  bytes = good_;
  bytes[bytes.size() - 1] ^= 0x80;
  expectRefused(bytes, "checksum mismatch");
}

TEST_F(BoostedFileCorruption, BadClassMap) {
  auto bytes = good_;
  bytes[classLabelOffset(3)] = 9;  // a label this build does not have
  fixChecksum(bytes);
  expectRefused(bytes, "bad class map");
  // A class count the booster does not answer: drop the last class's entry.
  bytes = good_;
  const int last = model_.internalClasses().count() - 1;
  const std::string& name = model_.internalClasses().names[static_cast<std::size_t>(last)];
  const std::size_t entry = classLabelOffset(last) - name.size() - 4;
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(entry),
              bytes.begin() + static_cast<std::ptrdiff_t>(classLabelOffset(last) + 1));
  // The count sits before the first class entry.
  const std::string& first = model_.internalClasses().names[0];
  putU32(bytes, classLabelOffset(0) - first.size() - 8, static_cast<std::uint32_t>(last));
  fixChecksum(bytes);
  expectRefused(bytes, "class count mismatch");
  // More classes than any model may have.
  bytes = good_;
  putU32(bytes, classLabelOffset(0) - first.size() - 8, 1000);
  fixChecksum(bytes);
  expectRefused(bytes, "bad class map");
}

TEST_F(BoostedFileCorruption, BadLearnerByteAndContextRound) {
  // The learner byte follows the label names.
  std::size_t offset = 12 + 4;
  for (auto name : kLabelNames) offset += 4 + name.size();
  auto bytes = good_;
  ASSERT_EQ(bytes[offset], 1u);
  bytes[offset] = 7;
  fixChecksum(bytes);
  expectRefused(bytes, "learner = 7");
  bytes = good_;
  bytes[bytes.size() - 10] = 1;  // a context round behind a booster
  fixChecksum(bytes);
  expectRefused(bytes, "auto-context round");
}

// ---------------------------------------------------------------------------
// Config and Segmenter

TEST(LearnerConfig, SettingsParseAndUnsupportedCombinationsAreRefused) {
  const Config c = parseConfig(
      "learner:\n  kind: xgboost\n  classes: nyu40\nxgboost:\n  rounds: 25\n  max_depth: 4\n"
      "  eta: 0.1\n  subsample: 0.8\n  colsample: 0.5\n  min_child_weight: 2\n  lambda: 3\n"
      "  seed: 9\n",
      "a.yaml");
  EXPECT_EQ(c.segmenter.learner.kind, LearnerKind::XGBoost);
  EXPECT_EQ(c.segmenter.learner.classes, ClassScheme::Nyu40);
  EXPECT_EQ(c.segmenter.xgboost.rounds, 25);
  EXPECT_EQ(c.segmenter.xgboost.max_depth, 4);
  EXPECT_DOUBLE_EQ(c.segmenter.xgboost.eta, 0.1);
  EXPECT_DOUBLE_EQ(c.segmenter.xgboost.subsample, 0.8);
  EXPECT_DOUBLE_EQ(c.segmenter.xgboost.colsample, 0.5);
  EXPECT_DOUBLE_EQ(c.segmenter.xgboost.min_child_weight, 2.0);
  EXPECT_DOUBLE_EQ(c.segmenter.xgboost.lambda, 3.0);
  EXPECT_EQ(c.segmenter.xgboost.seed, 9);
  EXPECT_EQ(SegmenterConfig{}.learner.kind, LearnerKind::Forest);
  EXPECT_EQ(SegmenterConfig{}.learner.classes, ClassScheme::Labels);
  EXPECT_EQ(SegmenterConfig{}.learner.class_weight, ClassWeight::Labels);
  EXPECT_EQ(parseConfig("learner:\n  class_weight: classes\n", "a.yaml").segmenter.learner.class_weight,
            ClassWeight::Classes);
  auto error = [](const std::string& yaml) {
    try {
      parseConfig(yaml, "a.yaml");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(error("learner:\n  kind: svm\n"), HasSubstr("learner.kind"));
  EXPECT_THAT(error("learner:\n  classes: nyu894\n"), HasSubstr("learner.classes"));
  EXPECT_THAT(error("learner:\n  class_weight: pixels\n"), HasSubstr("learner.class_weight"));
  EXPECT_THAT(error("xgboost:\n  eta: 0\n"), HasSubstr("xgboost.eta"));
  EXPECT_THAT(error("xgboost:\n  rounds: 0\n"), HasSubstr("xgboost.rounds"));
  EXPECT_THAT(error("learner:\n  kind: xgboost\nfeatures:\n  context: true\n"),
              HasSubstr("auto-context"));
  EXPECT_THAT(error("learner:\n  classes: nyu13\ntraining:\n  split_labels: nyu40\n"),
              HasSubstr("training.split_labels"));
}

// What a model is (learner.kind, learner.classes) is taken from it when the config does
// not give it (configForModel); a config giving another value (a file, --set) is refused
// naming the key and the model.
TEST(LearnerSegmenter, TakesTheModelsLearnerAndClassesAndRefusesOthersGiven) {
  const FineSet fine = makeFineBlobs(2, 10, 1, "nyu13");
  SegmenterConfig config;
  ASSERT_FALSE(config.regions.enabled);
  ASSERT_FALSE(config.scene.enabled);
  ASSERT_FALSE(config.context.enabled);
  auto given = [](const SegmenterConfig& c, std::initializer_list<const char*> settings) {
    Config out;
    out.segmenter = c;
    for (const char* kv : settings) applyOverride(out, kv);
    return out.segmenter;
  };
  auto expectRefused = [](const SegmenterConfig& c, const RandomForest& model,
                          const std::string& key) {
    try {
      Segmenter segmenter(c, std::make_shared<const RandomForest>(model));
      ADD_FAILURE() << "accepted a model that does not match " << key;
    } catch (const Error& e) {
      EXPECT_THAT(e.what(), HasSubstr(key + " (--set)"));
      EXPECT_THAT(e.what(), HasSubstr(model.id()));
    }
  };
  const RandomForest forest8 = RandomForest::train(labelsOnly(fine.set), {});
  RandomForest forest13 = RandomForest::train(fine.set, {});
  forest13.setInternalClasses(fine.classes);
  const RandomForest boosted13 =
      RandomForest::trainBoosted(fine.set, fine.classes, smallBooster(), true, 1);

  EXPECT_NO_THROW(Segmenter(config, std::make_shared<const RandomForest>(forest8)));
  const Segmenter taking13(config, std::make_shared<const RandomForest>(forest13));
  EXPECT_EQ(taking13.config().learner.classes, ClassScheme::Nyu13);
  const Segmenter taking_boosted(config, std::make_shared<const RandomForest>(boosted13));
  EXPECT_EQ(taking_boosted.config().learner.kind, LearnerKind::XGBoost);
  EXPECT_EQ(taking_boosted.config().learner.classes, ClassScheme::Nyu13);

  expectRefused(given(config, {"learner.classes=labels"}), forest13, "learner.classes = labels");
  expectRefused(given(config, {"learner.kind=forest"}), boosted13, "learner.kind = forest");
  const SegmenterConfig fine_forest = given(config, {"learner.classes=nyu13"});
  EXPECT_NO_THROW(Segmenter(fine_forest, std::make_shared<const RandomForest>(forest13)));
  expectRefused(fine_forest, forest8, "learner.classes = nyu13");
  const SegmenterConfig boosted = given(fine_forest, {"learner.kind=xgboost"});
  EXPECT_NO_THROW(Segmenter(boosted, std::make_shared<const RandomForest>(boosted13)));
  expectRefused(boosted, forest13, "learner.kind = xgboost");
  expectRefused(given(boosted, {"learner.classes=nyu40"}), boosted13, "learner.classes = nyu40");
}

// On real NYU frames: trainModel with learner.classes reads label13/ or
// label40/, learns (label, class) pairs, and both learners answer through
// predictSample with distributions over the 8 labels.
TEST(LearnerTraining, InternalClassesFromRealFramesForBothLearners) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  SegmenterConfig config;
  config.oversegmentation.kind = OversegmenterKind::Organized;
  config.ground.source = GroundSource::FloorLabels;
  config.forest.num_trees = 3;
  config.forest.num_threads = 1;
  config.xgboost = smallBooster();
  for (const ClassScheme scheme : {ClassScheme::Nyu13, ClassScheme::Nyu40}) {
    SCOPED_TRACE(classSchemeName(scheme));
    config.learner.classes = scheme;
    DatasetOptions options;
    options.fine_labels_folder = fineLabelsFolder(config, TrainingOptions{});
    EXPECT_EQ(options.fine_labels_folder, scheme == ClassScheme::Nyu13 ? "label13" : "label40");
    const DatasetFolder folder(dir.string(), options);
    LabeledFrames frames = framesOf(folder);
    frames.count = 3;
    ExtractionReport report;
    const auto samples = extractSamples(frames, Segmenter(config, nullptr), report);
    ASSERT_GE(samples.size(), 2u);
    std::vector<const FrameSample*> train;
    for (const auto& s : samples) train.push_back(&s);
    for (const LearnerKind kind : {LearnerKind::Forest, LearnerKind::XGBoost}) {
      SCOPED_TRACE(learnerKindName(kind));
      config.learner.kind = kind;
      const RandomForest model = trainModel(train, config);
      EXPECT_EQ(model.learnerKind(), kind);
      const InternalClasses& classes = model.internalClasses();
      EXPECT_EQ(classes.scheme, classSchemeName(scheme));
      EXPECT_GT(classes.count(), kNumLabels / 2);
      for (int c = 0; c < classes.count(); ++c) {
        // "label/class": the prefix is the label the class merges into.
        const std::string& name = classes.names[static_cast<std::size_t>(c)];
        EXPECT_EQ(name.substr(0, name.find('/')),
                  kLabelNames[classes.to_label[static_cast<std::size_t>(c)]])
            << name;
      }
      EXPECT_NO_THROW(Segmenter(config, std::make_shared<const RandomForest>(model)));
      const auto probs = predictSample(model, samples[0], config);
      ASSERT_EQ(probs.size(), samples[0].segment_labels.size());
      int right = 0, labelled = 0;
      for (std::size_t k = 0; k < probs.size(); ++k) {
        double sum = 0.0;
        for (float p : probs[k]) sum += p;
        ASSERT_NEAR(sum, 1.0, 1e-4) << k;
        if (samples[0].segment_labels[k] >= kNumLabels) continue;
        ++labelled;
        right += std::max_element(probs[k].begin(), probs[k].end()) - probs[k].begin() ==
                 samples[0].segment_labels[k];
      }
      // A training frame: most of its patches come back right.
      EXPECT_GT(right, labelled / 2);
    }
    config.learner.kind = LearnerKind::Forest;
  }
}

}  // namespace
}  // namespace findmug
