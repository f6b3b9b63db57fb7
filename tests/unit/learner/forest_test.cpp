// Tests of the randomized decision forest: learning, determinism, the model
// file and its refusal of truncated/corrupt/foreign files.
#include "findmug/learner/forest.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <random>
#include <thread>

#include "findmug/common/error.hpp"
#include "learner/forest_format.hpp"  // internal: file layout and checksum (src/)
#include "test_data.hpp"
#include "file_bytes.hpp"
#include "model_bytes.hpp"

namespace findmug {
namespace {

using test::TempDir;

// 8 well separated Gaussian blobs in 14-D, one per label.
TrainingSet makeBlobs(int per_class, std::uint32_t seed, float noise = 0.6f) {
  std::mt19937 mean_rng(1234);  // same class means for every call
  std::uniform_real_distribution<float> mean_dist(0.0f, 10.0f);
  std::array<FeatureVector, kNumLabels> means;
  for (auto& m : means)
    for (float& v : m) v = mean_dist(mean_rng);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise_dist(0.0f, noise);
  TrainingSet set;
  for (int i = 0; i < per_class; ++i) {
    for (int c = 0; c < kNumLabels; ++c) {
      FeatureVector x;
      for (int f = 0; f < kFeatureDim; ++f) x[f] = means[c][f] + noise_dist(rng);
      set.features.push_back(x);
      set.labels.push_back(static_cast<std::uint8_t>(c));
    }
  }
  return set;
}

int argmax(const ClassProbabilities& p) {
  return static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin());
}

double accuracy(const RandomForest& forest, const TrainingSet& set) {
  int correct = 0;
  for (std::size_t i = 0; i < set.features.size(); ++i)
    correct += argmax(forest.predict(set.features[i])) == set.labels[i];
  return static_cast<double>(correct) / static_cast<double>(set.features.size());
}

// Every probability non-negative, summing to one.
void expectDistribution(const ClassProbabilities& p) {
  float sum = 0.0f;
  for (float v : p) {
    EXPECT_GE(v, 0.0f);
    sum += v;
  }
  EXPECT_NEAR(sum, 1.0f, 1e-5f);
}

using test::readBytes;
using test::fixChecksum;
using test::putU32;
using test::writeBytes;

// ---------------------------------------------------------------------------
// Learning

TEST(Forest, LearnsSeparableProblem) {
  const TrainingSet train = makeBlobs(200, 1);
  const TrainingSet test = makeBlobs(100, 2);
  ForestParams params;
  params.num_trees = 8;
  params.max_depth = 12;
  const RandomForest forest = RandomForest::train(train, params);
  EXPECT_EQ(forest.trees().size(), 8u);
  EXPECT_GT(accuracy(forest, test), 0.95);
  // Every prediction is a distribution.
  for (std::size_t i = 0; i < 50; ++i) expectDistribution(forest.predict(test.features[i]));
}

TEST(Forest, DeeperTreesFitBetterThanStumps) {
  // Noisier blobs: 8 classes cannot be told apart by one split per tree.
  const TrainingSet train = makeBlobs(150, 3, 1.5f);
  ForestParams shallow;
  shallow.max_depth = 1;
  ForestParams deep;
  deep.max_depth = 12;
  const double shallow_acc = accuracy(RandomForest::train(train, shallow), train);
  const double deep_acc = accuracy(RandomForest::train(train, deep), train);
  // Measured: stumps ~0.69, depth 12 ~1.0 (seeds 1..3).
  EXPECT_GT(deep_acc, 0.95);
  EXPECT_LT(shallow_acc, 0.85);
  EXPECT_GT(deep_acc, shallow_acc + 0.15) << "shallow " << shallow_acc << " deep " << deep_acc;
}

TEST(Forest, RespectsDepthAndMinSamplesPerLeaf) {
  const TrainingSet train = makeBlobs(60, 4, 2.0f);
  ForestParams params;
  params.num_trees = 3;
  params.max_depth = 5;
  params.min_samples_leaf = 7;
  params.class_weighting = false;
  const RandomForest forest = RandomForest::train(train, params);
  for (const auto& tree : forest.trees()) {
    // Depth of every node, and how many training samples reach each leaf
    // (no bagging, so every tree saw all samples).
    std::vector<int> depth(tree.size(), 0);
    for (std::size_t i = 0; i < tree.size(); ++i) {
      if (tree[i].feature >= 0) {
        depth[tree[i].left] = depth[i] + 1;
        depth[tree[i].right] = depth[i] + 1;
      }
    }
    EXPECT_LE(*std::max_element(depth.begin(), depth.end()), 5);
    EXPECT_GT(tree.size(), 1u);
    std::vector<int> reached(tree.size(), 0);
    for (const auto& x : train.features) {
      std::int32_t i = 0;
      while (tree[i].feature >= 0)
        i = x[tree[i].feature] < tree[i].threshold ? tree[i].left : tree[i].right;
      ++reached[i];
    }
    for (std::size_t i = 0; i < tree.size(); ++i) {
      if (tree[i].feature < 0) {
        EXPECT_GE(reached[i], 7) << "leaf " << i;
        float sum = 0.0f;
        for (float p : tree[i].distribution) sum += p;
        EXPECT_NEAR(sum, 1.0f, 1e-5f);
      }
    }
  }
}

TEST(Forest, PureDataGivesSingleLeaf) {
  TrainingSet train = makeBlobs(20, 5);
  std::fill(train.labels.begin(), train.labels.end(), static_cast<std::uint8_t>(Label::Table));
  const RandomForest forest = RandomForest::train(train, ForestParams{});
  for (const auto& tree : forest.trees()) {
    ASSERT_EQ(tree.size(), 1u);
    EXPECT_EQ(tree[0].feature, -1);
    EXPECT_FLOAT_EQ(tree[0].distribution[static_cast<int>(Label::Table)], 1.0f);
  }
}

TEST(Forest, LeafHistogramUsesSampleAndClassWeights) {
  // All features equal: no split possible, the root is the leaf.
  TrainingSet train;
  for (int i = 0; i < 20; ++i) {
    train.features.push_back(FeatureVector{});
    const bool wall = i < 10;
    train.labels.push_back(wall ? 2 : 7);
    train.weights.push_back(wall ? 3.0f : 1.0f);
  }
  ForestParams params;
  params.num_trees = 1;
  params.class_weighting = false;
  auto p = RandomForest::train(train, params).predict(FeatureVector{});
  EXPECT_NEAR(p[2], 0.75f, 1e-6f);
  EXPECT_NEAR(p[7], 0.25f, 1e-6f);
  params.class_weighting = true;  // each class then carries the same total weight
  p = RandomForest::train(train, params).predict(FeatureVector{});
  EXPECT_NEAR(p[2], 0.5f, 1e-6f);
  EXPECT_NEAR(p[7], 0.5f, 1e-6f);
}

// forest.shrinkage: a pure leaf under a mixed root is pulled towards the root
// by 1 / (1 + lambda / N_root); 0 leaves the histograms as they are; on a
// deeper forest every leaf stays a distribution, less sure than without.
TEST(Forest, ShrinkagePullsLeavesTowardsTheirAncestors) {
  TrainingSet train;
  for (int i = 0; i < 20; ++i) {
    FeatureVector x{};
    x[0] = i < 10 ? 0.0f : 1.0f;
    train.features.push_back(x);
    train.labels.push_back(i < 10 ? 2 : 4);  // wall | table
  }
  ForestParams params;
  params.num_trees = 1;
  params.max_depth = 1;
  params.min_samples_leaf = 1;
  params.candidate_features = kFeatureDim;  // the one useful feature is always tried
  params.class_weighting = false;
  FeatureVector wall_side{};
  auto p = RandomForest::train(train, params).predict(wall_side);
  EXPECT_FLOAT_EQ(p[2], 1.0f);
  params.shrinkage = 20.0;  // damping 1 / (1 + 20 / 20) = 0.5: 0.5 + 0.5 * 0.5
  p = RandomForest::train(train, params).predict(wall_side);
  EXPECT_NEAR(p[2], 0.75f, 1e-6f);
  EXPECT_NEAR(p[4], 0.25f, 1e-6f);

  const TrainingSet blobs = makeBlobs(40, 3, 2.5f);
  ForestParams deep;
  deep.num_trees = 4;
  const RandomForest sharp = RandomForest::train(blobs, deep);
  deep.shrinkage = 50.0;
  const RandomForest shrunk = RandomForest::train(blobs, deep);
  double sharp_max = 0, shrunk_max = 0;
  for (std::size_t i = 0; i < blobs.features.size(); ++i) {
    const auto a = sharp.predict(blobs.features[i]);
    const auto b = shrunk.predict(blobs.features[i]);
    expectDistribution(b);
    sharp_max += *std::max_element(a.begin(), a.end());
    shrunk_max += *std::max_element(b.begin(), b.end());
  }
  EXPECT_LT(shrunk_max, sharp_max);
  deep.shrinkage = -1.0;
  EXPECT_THROW(RandomForest::train(blobs, deep), Error);
}

// A rare class overlapping a frequent one: chair (5 %) vs wall, shifted in one
// feature. Without weighting the leaves in the overlap vote wall.
TrainingSet makeRareClassSet(std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> unit(0.0f, 1.0f);
  TrainingSet set;
  auto add = [&](std::uint8_t label, float shift, int count) {
    for (int i = 0; i < count; ++i) {
      FeatureVector x;
      for (float& v : x) v = unit(rng);
      x[3] += shift;
      set.features.push_back(x);
      set.labels.push_back(label);
    }
  };
  add(static_cast<std::uint8_t>(Label::Wall), 0.0f, 3000);
  add(static_cast<std::uint8_t>(Label::Chair), 1.5f, 150);
  return set;
}

double recall(const RandomForest& forest, const TrainingSet& set, int label) {
  int hits = 0, total = 0;
  for (std::size_t i = 0; i < set.features.size(); ++i) {
    if (set.labels[i] != label) continue;
    ++total;
    hits += argmax(forest.predict(set.features[i])) == label;
  }
  return static_cast<double>(hits) / total;
}

TEST(Forest, ClassWeightingRaisesRecallOfRareClass) {
  const TrainingSet train = makeRareClassSet(10);
  const TrainingSet test = makeRareClassSet(11);
  ForestParams params;
  params.max_depth = 8;
  params.min_samples_leaf = 30;
  params.class_weighting = false;
  const double plain = recall(RandomForest::train(train, params), test, 5);
  params.class_weighting = true;
  const double weighted = recall(RandomForest::train(train, params), test, 5);
  // Measured: plain ~0.0-0.02, weighted ~0.6.
  EXPECT_GT(weighted, plain + 0.3) << "plain " << plain << " weighted " << weighted;
}

// ---------------------------------------------------------------------------
// Determinism and progress

TEST(Forest, SameSeedGivesIdenticalModelWhateverTheThreadCount) {
  const TrainingSet train = makeBlobs(40, 6, 2.0f);
  TempDir dir;
  ForestParams params;
  params.num_trees = 6;
  params.bagging_fraction = 0.7;
  std::vector<std::vector<std::uint8_t>> files;
  std::vector<std::string> ids;
  for (int threads : {1, 2, 3, 6, 0}) {
    params.num_threads = threads;
    const RandomForest forest = RandomForest::train(train, params);
    const std::string path = dir.str("t" + std::to_string(threads) + ".fmf");
    forest.save(path);
    files.push_back(readBytes(path));
    ids.push_back(forest.id());
  }
  ASSERT_FALSE(files[0].empty());
  for (std::size_t i = 1; i < files.size(); ++i) {
    EXPECT_EQ(ids[i], ids[0]);
    EXPECT_TRUE(files[i] == files[0]) << "model " << i << " differs";
  }
  // A different seed gives a different model.
  params.seed = 43;
  EXPECT_NE(RandomForest::train(train, params).id(), ids[0]);
}

TEST(Forest, ProgressReportedOnCallingThreadForEveryTree) {
  const TrainingSet train = makeBlobs(20, 7);
  ForestParams params;
  params.num_trees = 5;
  params.num_threads = 2;
  std::vector<std::pair<int, int>> calls;
  const auto caller = std::this_thread::get_id();
  bool other_thread = false;
  RandomForest::train(train, params, [&](int done, int total) {
    calls.emplace_back(done, total);
    other_thread |= std::this_thread::get_id() != caller;
  });
  ASSERT_EQ(calls.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(calls[i], std::make_pair(i + 1, 5));
  EXPECT_FALSE(other_thread);
}

TEST(Forest, ProgressCallbackExceptionPropagates) {
  const TrainingSet train = makeBlobs(20, 7);
  ForestParams params;
  params.num_trees = 4;
  params.num_threads = 2;
  EXPECT_THROW(
      RandomForest::train(train, params, [](int, int) { throw std::runtime_error("cancelled"); }),
      std::runtime_error);
}

// ---------------------------------------------------------------------------
// Input validation

TEST(Forest, RefusesBadTrainingInput) {
  const TrainingSet good = makeBlobs(5, 8);
  ForestParams params;
  auto expectError = [&](const TrainingSet& set, const ForestParams& p, const std::string& word) {
    try {
      RandomForest::train(set, p);
      ADD_FAILURE() << "no error, expected one mentioning " << word;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  expectError(TrainingSet{}, params, "empty");
  TrainingSet bad = good;
  bad.labels.pop_back();
  expectError(bad, params, "labels");
  bad = good;
  bad.labels[3] = kVoidLabel;
  expectError(bad, params, "label 255");
  bad = good;
  bad.features[2][4] = std::nanf("");
  expectError(bad, params, "min_height");
  bad = good;
  bad.weights.assign(good.labels.size(), 1.0f);
  bad.weights[1] = 0.0f;
  expectError(bad, params, "weight");
  bad.weights.resize(3);
  expectError(bad, params, "weights");
  ForestParams p = params;
  p.num_trees = 0;
  expectError(good, p, "num_trees");
  p = params;
  p.candidate_features = 15;
  expectError(good, p, "candidate_features");
  p = params;
  p.bagging_fraction = 0.0;
  expectError(good, p, "bagging_fraction");
  p = params;
  p.min_samples_leaf = 0;
  expectError(good, p, "min_samples_leaf");
  bad = good;
  bad.split_labels.assign(good.labels.size() - 1, 0);
  bad.split_classes = 3;
  expectError(bad, params, "split labels");
  bad.split_labels.assign(good.labels.size(), 0);
  bad.split_labels[4] = 3;
  expectError(bad, params, "split label 3");
  bad.split_labels[4] = 0;
  bad.split_classes = kMaxSplitClasses + 1;
  expectError(bad, params, "split_classes");
  EXPECT_THROW(RandomForest().predict(FeatureVector{}), Error);
}

// Split labels equal to the labels are no change at all: the same model,
// byte for byte (the split code path is shared).
TEST(Forest, SplitLabelsEqualToTheLabelsGiveTheSameModel) {
  TempDir dir;
  const TrainingSet plain = makeBlobs(30, 5, 3.0f);
  TrainingSet split = plain;
  split.split_labels = plain.labels;
  split.split_classes = kNumLabels;
  ForestParams params;
  params.num_trees = 3;
  params.max_depth = 6;
  RandomForest::train(plain, params).save(dir.str("plain.fmf"));
  RandomForest::train(split, params).save(dir.str("split.fmf"));
  EXPECT_EQ(readBytes(dir.str("plain.fmf")), readBytes(dir.str("split.fmf")));
}

// Class A is made of two kinds (split classes 1 and 2) at either end of
// feature 0, class B (split class 3) is spread over it; feature 1 tells A
// from B only in part. On the labels feature 0 has no gain (both sides are
// 2/3 A) and the stump splits on feature 1; on the split labels feature 0
// separates the two kinds of A and wins. The leaves still hold labels A and B.
TEST(Forest, SplitLabelsChooseSplitsTheLabelsCannotSee) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  TrainingSet set;
  constexpr std::uint8_t kA = 3, kB = 5;  // any two findmug labels
  for (int i = 0; i < 300; ++i) {
    const int kind = i % 3;  // 0: A of kind 1, 1: A of kind 2, 2: B
    FeatureVector x{};
    x[0] = kind == 0 ? unit(rng) : kind == 1 ? 2.0f + unit(rng) : 3.0f * unit(rng);
    x[1] = kind == 2 ? 0.5f + unit(rng) : unit(rng);
    set.features.push_back(x);
    set.labels.push_back(kind == 2 ? kB : kA);
    set.split_labels.push_back(static_cast<std::uint8_t>(kind + 1));
  }
  set.split_classes = 4;  // 0 unused, as with NYU-40 ids
  ForestParams params;
  params.num_trees = 1;
  params.max_depth = 1;
  params.candidate_features = kFeatureDim;
  params.candidate_thresholds = 200;
  params.class_weighting = false;
  TrainingSet coarse = set;
  coarse.split_labels.clear();
  coarse.split_classes = 0;
  const RandomForest by_labels = RandomForest::train(coarse, params);
  const RandomForest by_split = RandomForest::train(set, params);
  ASSERT_EQ(by_labels.trees()[0].size(), 3u);
  ASSERT_EQ(by_split.trees()[0].size(), 3u);
  EXPECT_EQ(by_labels.trees()[0][0].feature, 1);
  EXPECT_EQ(by_split.trees()[0][0].feature, 0);
  EXPECT_GT(by_split.trees()[0][0].threshold, 1.0f);
  EXPECT_LT(by_split.trees()[0][0].threshold, 2.0f);
  for (int leaf : {1, 2}) {
    const auto& d = by_split.trees()[0][static_cast<std::size_t>(leaf)].distribution;
    EXPECT_NEAR(d[kA] + d[kB], 1.0f, 1e-5f);  // leaves hold labels, not split classes
    EXPECT_NEAR(d[kA], 2.0f / 3.0f, 0.1f);
  }
}

// ---------------------------------------------------------------------------
// Model file

TEST(ForestFile, SaveLoadRoundTripGivesIdenticalPredictions) {
  const TrainingSet train = makeBlobs(50, 9, 1.5f);
  const TrainingSet test = makeBlobs(30, 10, 1.5f);
  ForestParams params;
  params.num_trees = 4;
  params.max_depth = 9;
  params.bagging_fraction = 0.8;
  params.seed = 777;
  const RandomForest forest = RandomForest::train(train, params);
  TempDir dir;
  const std::string path = dir.str("model.fmf");
  forest.save(path);
  const RandomForest loaded = RandomForest::load(path);
  EXPECT_EQ(loaded.id(), forest.id());
  EXPECT_EQ(forest.id().size(), 8u);
  EXPECT_EQ(loaded.params().seed, 777u);
  EXPECT_EQ(loaded.params().max_depth, 9);
  EXPECT_EQ(loaded.params().bagging_fraction, 0.8);
  EXPECT_EQ(loaded.params().class_weighting, true);
  ASSERT_EQ(loaded.trees().size(), forest.trees().size());
  for (const auto& x : test.features) {
    const auto a = forest.predict(x);
    const auto b = loaded.predict(x);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof a), 0);
  }
  // Saving the loaded model reproduces the file byte for byte.
  loaded.save(dir.str("again.fmf"));
  EXPECT_EQ(readBytes(dir.str("again.fmf")), readBytes(path));
}

// The internal format header (src/learner/forest_format.hpp) is what save() writes:
// serialize() gives the file's bytes, which start with the magic and version
// and end with the FNV-1a 64 of the rest; id() is idFromChecksum of it.
TEST(ForestFile, FileIsSerializeEndingInItsChecksumAndTheIdComesFromIt) {
  const RandomForest forest = RandomForest::train(makeBlobs(20, 12), ForestParams{});
  TempDir dir;
  const std::string path = dir.str("model.fmf");
  forest.save(path);
  const std::vector<std::uint8_t> bytes = readBytes(path);
  EXPECT_EQ(forest_format::serialize(forest), bytes);
  ASSERT_GT(bytes.size(), sizeof forest_format::kMagic + 4 + forest_format::kChecksumSize);
  EXPECT_EQ(std::memcmp(bytes.data(), forest_format::kMagic, sizeof forest_format::kMagic), 0);
  std::uint32_t version = 0;
  for (int i = 0; i < 4; ++i)
    version |= static_cast<std::uint32_t>(bytes[sizeof forest_format::kMagic + i]) << (8 * i);
  EXPECT_EQ(version, forest_format::kFormatVersion);
  const std::size_t body = bytes.size() - forest_format::kChecksumSize;
  std::uint64_t stored = 0;
  for (std::size_t i = 0; i < forest_format::kChecksumSize; ++i)
    stored |= static_cast<std::uint64_t>(bytes[body + i]) << (8 * i);
  EXPECT_EQ(stored, forest_format::fnv1a64(bytes.data(), body));
  EXPECT_EQ(forest.id(), forest_format::idFromChecksum(stored));
  EXPECT_EQ(RandomForest::load(path).id(), forest.id());
  // FNV-1a 64 of nothing and of "a" (published test vectors).
  EXPECT_EQ(forest_format::fnv1a64(nullptr, 0), 0xcbf29ce484222325ULL);
  const std::uint8_t a = 'a';
  EXPECT_EQ(forest_format::fnv1a64(&a, 1), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(forest_format::idFromChecksum(0x0123456789abcdefULL), "01234567");
}

TEST(ForestFile, ExtractionSettingsRoundTripAndChangeTheId) {
  RandomForest forest = RandomForest::train(makeBlobs(20, 3), ForestParams{});
  const std::string bare_id = forest.id();
  forest.setExtractionSettings(
      {{"oversegmentation.method", "organized"}, {"normals.window_radius_px", "4"}});
  EXPECT_NE(forest.id(), bare_id);  // the id names the content, settings included
  TempDir dir;
  forest.save(dir.str("m.fmf"));
  const RandomForest loaded = RandomForest::load(dir.str("m.fmf"));
  EXPECT_EQ(loaded.id(), forest.id());
  EXPECT_EQ(loaded.source(), dir.str("m.fmf"));
  ASSERT_EQ(loaded.extractionSettings().size(), 2u);
  EXPECT_EQ(loaded.extractionSettings()[0].first, "oversegmentation.method");
  EXPECT_EQ(loaded.extractionSettings()[0].second, "organized");
  EXPECT_THROW(forest.setExtractionSettings({{"", "x"}}), Error);
}

// Blobs with `extra` more columns: the class mean on the first extra column,
// noise on the others.
TrainingSet withExtraColumns(TrainingSet set, int extra, const std::string& prefix) {
  std::mt19937 rng(99);
  std::normal_distribution<float> noise(0.0f, 0.3f);
  for (int e = 0; e < extra; ++e) set.extra_names.push_back(prefix + std::to_string(e));
  for (std::size_t i = 0; i < set.labels.size(); ++i) {
    for (int e = 0; e < extra; ++e)
      set.extra.push_back((e == 0 ? 3.0f * set.labels[i] : 0.0f) + noise(rng));
  }
  return set;
}

TEST(ForestFile, ExtraColumnsAndContextRoundRoundTrip) {
  const TrainingSet first_set = withExtraColumns(makeBlobs(30, 21, 8.0f), 3, "region_");
  ForestParams params;
  params.num_trees = 3;
  params.seed = 11;
  RandomForest forest = RandomForest::train(first_set, params);
  ASSERT_EQ(forest.dim(), kFeatureDim + 3);
  EXPECT_EQ(forest.featureNames()[kFeatureDim], "region_0");
  // The extra column carries the class: a forest of 17 columns uses it.
  bool uses_extra = false;
  for (const auto& tree : forest.trees())
    for (const auto& node : tree) uses_extra |= node.feature >= kFeatureDim;
  EXPECT_TRUE(uses_extra);

  TrainingSet second_set = first_set;
  for (int e = 0; e < 2; ++e) second_set.extra_names.push_back("ctx_" + std::to_string(e));
  second_set.extra.clear();
  for (std::size_t i = 0; i < first_set.labels.size(); ++i) {
    for (int e = 0; e < 3; ++e) second_set.extra.push_back(first_set.extra[i * 3 + e]);
    second_set.extra.push_back(static_cast<float>(first_set.labels[i]));
    second_set.extra.push_back(0.5f);
  }
  const std::string first_id = forest.id();
  forest.setContextRound(RandomForest::train(second_set, params));
  EXPECT_NE(forest.id(), first_id);  // the id names the context round too
  ASSERT_NE(forest.contextRound(), nullptr);
  EXPECT_EQ(forest.contextRound()->dim(), kFeatureDim + 5);

  TempDir dir;
  forest.save(dir.str("two-stage.fmf"));
  const RandomForest loaded = RandomForest::load(dir.str("two-stage.fmf"));
  EXPECT_EQ(loaded.id(), forest.id());
  EXPECT_EQ(loaded.formatVersion(), 5u);
  EXPECT_EQ(loaded.featureNames(), forest.featureNames());
  ASSERT_NE(loaded.contextRound(), nullptr);
  EXPECT_EQ(loaded.contextRound()->featureNames(), forest.contextRound()->featureNames());
  for (std::size_t i = 0; i < 40; ++i) {
    std::vector<float> row(first_set.features[i].begin(), first_set.features[i].end());
    row.insert(row.end(), first_set.extra.begin() + 3 * i, first_set.extra.begin() + 3 * i + 3);
    auto a = forest.predict(row), b = loaded.predict(row);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof a), 0);
    row.push_back(static_cast<float>(first_set.labels[i]));
    row.push_back(0.5f);
    a = forest.contextRound()->predict(row);
    b = loaded.contextRound()->predict(row);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof a), 0);
  }
  loaded.save(dir.str("again.fmf"));
  EXPECT_EQ(readBytes(dir.str("again.fmf")), readBytes(dir.str("two-stage.fmf")));

  // Rows of the wrong length are refused, not read out of bounds.
  EXPECT_THROW(forest.predict(FeatureVector{}), Error);
  EXPECT_THROW(forest.predict(std::vector<float>(kFeatureDim + 4, 0.0f)), Error);
}

// A term as findmug-train learns it (mrf.pairwise = context), with values
// that do not survive a float32 round trip, so a narrowing writer is caught.
PairwiseContext learnedLookingTerm() {
  PairwiseContext term;
  term.bias = 1.2345678901234567;
  term.weights = {-0.8123456789012345, -1.1, -2.7, -0.3333333333333333};
  term.mean = {4.1, 6.2, 0.08, 0.21};
  term.scale = {5.5, 7.25, 0.11, 0.4};
  term.mean_cost = 3.1415926535897931;
  term.training_edges = 133071;
  return term;
}

TEST(ForestFile, PairwiseTermRoundTripsAndNamesTheModel) {
  ForestParams params;
  params.num_trees = 2;
  params.seed = 3;
  RandomForest forest = RandomForest::train(makeBlobs(10, 4), params);
  EXPECT_EQ(forest.pairwiseContext(), nullptr);
  const std::string plain_id = forest.id();
  EXPECT_EQ(forest.summary().find("pairwise"), std::string::npos);
  forest.setPairwiseContext(learnedLookingTerm());
  EXPECT_NE(forest.id(), plain_id);  // the id names the term too
  EXPECT_NE(forest.summary().find("learned pairwise term"), std::string::npos) << forest.summary();

  TempDir dir;
  forest.save(dir.str("term.fmf"));
  const RandomForest loaded = RandomForest::load(dir.str("term.fmf"));
  EXPECT_EQ(loaded.formatVersion(), 5u);
  EXPECT_EQ(loaded.id(), forest.id());
  ASSERT_NE(loaded.pairwiseContext(), nullptr);
  EXPECT_EQ(*loaded.pairwiseContext(), learnedLookingTerm());  // bit-exact, doubles kept
  loaded.save(dir.str("again.fmf"));
  EXPECT_EQ(readBytes(dir.str("again.fmf")), readBytes(dir.str("term.fmf")));

  // A term that cannot be used is refused when it is set, naming the field.
  PairwiseContext bad = learnedLookingTerm();
  bad.scale[2] = 0.0;
  EXPECT_THAT([&] { forest.setPairwiseContext(bad); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("scale")));
  // Removing it gives the plain forest back.
  forest.setPairwiseContext(std::nullopt);
  EXPECT_EQ(forest.id(), plain_id);
}

TEST(ForestFile, ContextRoundMustExtendTheFirstRound) {
  ForestParams params;
  params.num_trees = 1;
  const TrainingSet base = makeBlobs(10, 3);
  RandomForest plain = RandomForest::train(base, params);
  // Same columns only: nothing added.
  EXPECT_THROW(plain.setContextRound(RandomForest::train(base, params)), Error);
  // Different leading columns.
  RandomForest regions = RandomForest::train(withExtraColumns(base, 2, "region_"), params);
  EXPECT_THROW(regions.setContextRound(
                   RandomForest::train(withExtraColumns(base, 3, "other_"), params)),
               Error);
  EXPECT_NO_THROW(
      plain.setContextRound(RandomForest::train(withExtraColumns(base, 2, "c_"), params)));
}

TEST(Forest, RefusesBadExtraColumns) {
  TrainingSet set = withExtraColumns(makeBlobs(5, 1), 2, "x");
  set.extra.pop_back();
  EXPECT_THROW(RandomForest::train(set, ForestParams{}), Error);
  set = withExtraColumns(makeBlobs(5, 1), 2, "x");
  set.extra[3] = std::nanf("");
  EXPECT_THROW(RandomForest::train(set, ForestParams{}), Error);
  set = withExtraColumns(makeBlobs(5, 1), 2, "x");
  ForestParams params;
  params.candidate_features = kFeatureDim + 3;  // more than the 16 columns
  EXPECT_THROW(RandomForest::train(set, params), Error);
  params.candidate_features = kFeatureDim + 2;
  EXPECT_NO_THROW(RandomForest::train(set, params));
}

TEST(ForestFile, SaveToUnwritablePlaceFails) {
  const RandomForest forest = RandomForest::train(makeBlobs(5, 1), ForestParams{});
  EXPECT_THROW(forest.save("/nonexistent-dir-findmug/model.fmf"), Error);
  EXPECT_THROW(RandomForest().save("/tmp/findmug-empty.fmf"), Error);
}

// Reading a field by the documented file layout (src/learner/forest_format.hpp); the
// writing helpers are in tests/support/model_bytes.hpp.
std::uint32_t getU32(const std::vector<std::uint8_t>& bytes, std::size_t offset) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(bytes[offset + i]) << (8 * i);
  return v;
}

constexpr std::size_t kVersionOffset = 8;
constexpr std::size_t kLabelCountOffset = 12;
constexpr std::size_t kParamsSize = 5 * 4 + 1 + 8 + 8;

std::size_t labelsEndOffset() {
  std::size_t offset = kLabelCountOffset + 4;
  for (auto name : kLabelNames) offset += 4 + name.size();
  return offset;
}
// Format 4's learner byte and class map of a forest on the 8 labels: uint8
// learner, scheme "labels", uint32 count, per class name + uint8 label.
std::size_t learnerBlockSize() {
  std::size_t size = 1 + 4 + std::string("labels").size() + 4;
  for (auto name : kLabelNames) size += 4 + name.size() + 1;
  return size;
}
std::size_t featureSectionOffset() { return labelsEndOffset() + learnerBlockSize(); }
std::size_t paramsOffset() {
  std::size_t offset = featureSectionOffset() + 4;
  for (auto name : kFeatureNames) offset += 4 + name.size();
  return offset;
}
// The extraction-settings section follows the params; the fixture's forest
// has none, so it is just its uint32 count (0).
std::size_t settingsCountOffset() { return paramsOffset() + kParamsSize; }
std::size_t treeCountOffset() { return settingsCountOffset() + 4; }

// Offsets of the nodes of tree 0.
std::vector<std::size_t> nodeOffsetsOfFirstTree(const std::vector<std::uint8_t>& bytes) {
  std::size_t offset = treeCountOffset() + 4;
  const std::uint32_t count = getU32(bytes, offset);
  offset += 4;
  std::vector<std::size_t> nodes;
  for (std::uint32_t i = 0; i < count; ++i) {
    nodes.push_back(offset);
    const auto feature = static_cast<std::int32_t>(getU32(bytes, offset));
    offset += feature >= 0 ? 16 : 4 + 4 * kNumLabels;
  }
  return nodes;
}

class ForestFileCorruption : public ::testing::Test {
 protected:
  void SetUp() override {
    ForestParams params;
    params.num_trees = 2;
    params.max_depth = 3;
    params.seed = 5;
    forest_ = RandomForest::train(makeBlobs(10, 12, 2.0f), params);
    path_ = dir_.str("model.fmf");
    forest_.save(path_);
    good_ = readBytes(path_);
    ASSERT_GT(good_.size(), 400u);
    // Sanity of the layout helpers against the real file.
    ASSERT_EQ(getU32(good_, kLabelCountOffset), static_cast<std::uint32_t>(kNumLabels));
    ASSERT_EQ(getU32(good_, featureSectionOffset()), static_cast<std::uint32_t>(kFeatureDim));
    ASSERT_EQ(getU32(good_, treeCountOffset()), 2u);
  }

  void expectRefused(const std::vector<std::uint8_t>& bytes, const std::string& word) {
    test::expectModelRefused(dir_.str("bad.fmf"), bytes, word);
  }

  // `bytes` stamped as format `version` (checksum fixed), written and loaded: an
  // older writer's file, made from this one.
  RandomForest loadAsFormat(std::vector<std::uint8_t> bytes, std::uint32_t version) {
    putU32(bytes, kVersionOffset, version);
    fixChecksum(bytes);
    const std::string old = dir_.str("format" + std::to_string(version) + ".fmf");
    writeBytes(old, bytes);
    return RandomForest::load(old);
  }

  TempDir dir_;
  RandomForest forest_;
  std::string path_;
  std::vector<std::uint8_t> good_;
};

TEST_F(ForestFileCorruption, IntactFileLoads) {
  EXPECT_EQ(RandomForest::load(path_).id(), forest_.id());
}

TEST_F(ForestFileCorruption, MissingFile) {
  try {
    RandomForest::load(dir_.str("nope.fmf"));
    ADD_FAILURE() << "loaded a missing file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nope.fmf"), std::string::npos) << e.what();
  }
}

TEST_F(ForestFileCorruption, EveryTruncationIsRefused) {
  for (std::size_t length = 0; length < good_.size(); ++length) {
    SCOPED_TRACE("prefix length " + std::to_string(length));
    expectRefused(std::vector<std::uint8_t>(good_.begin(), good_.begin() + length), "truncated");
  }
}

TEST_F(ForestFileCorruption, EveryCorruptByteIsRefused) {
  // Low and high bits alternately: both a tiny float change and a sign/count
  // change must be caught.
  for (std::size_t i = 0; i < good_.size(); ++i) {
    const std::uint8_t flip = i % 2 ? 0x80 : 0x01;
    auto bytes = good_;
    bytes[i] ^= flip;
    SCOPED_TRACE("byte " + std::to_string(i) + " xor " + std::to_string(flip));
    expectRefused(bytes, "");
  }
}

TEST_F(ForestFileCorruption, CorruptLeafProbabilityIsAChecksumMismatch) {
  const auto nodes = nodeOffsetsOfFirstTree(good_);
  const auto leaf = std::find_if(nodes.begin(), nodes.end(), [&](std::size_t off) {
    return static_cast<std::int32_t>(getU32(good_, off)) < 0;
  });
  ASSERT_NE(leaf, nodes.end());
  auto bytes = good_;
  bytes[*leaf + 4] ^= 0x01;  // lowest mantissa bit of the first probability
  expectRefused(bytes, "checksum mismatch");
}

TEST_F(ForestFileCorruption, TrailingBytes) {
  auto bytes = good_;
  bytes.insert(bytes.end() - 8, std::uint8_t{0});
  fixChecksum(bytes);
  expectRefused(bytes, "unexpected bytes");
}

TEST_F(ForestFileCorruption, AbsurdExtractionSettingCount) {
  auto bytes = good_;
  ASSERT_EQ(getU32(bytes, settingsCountOffset()), 0u);
  putU32(bytes, settingsCountOffset(), 100000);
  fixChecksum(bytes);
  expectRefused(bytes, "extraction setting count");
}

TEST_F(ForestFileCorruption, WrongMagic) {
  auto bytes = good_;
  bytes[0] = 'X';
  expectRefused(bytes, "wrong magic");
  expectRefused({'P', 'K', 3, 4, 0, 0, 0, 0, 0}, "wrong magic");
}

TEST_F(ForestFileCorruption, WrongVersion) {
  auto bytes = good_;
  putU32(bytes, kVersionOffset, 1);  // the format before extraction settings were stored
  expectRefused(bytes, "version 1");
  putU32(bytes, kVersionOffset, 6);
  expectRefused(bytes, "version 6");
  fixChecksum(bytes);
  expectRefused(bytes, "version 6");
}

// Format 2 (before extra columns and context rounds): the same layout
// without the context-round flag. Such files still load, as 14-column
// forests without a context round.
TEST_F(ForestFileCorruption, Format2FileLoadsAsFourteenColumnsWithoutContextRound) {
  auto bytes = good_;
  ASSERT_EQ(getU32(bytes, kVersionOffset), 5u);
  ASSERT_EQ(bytes[bytes.size() - 10], 0u);  // the context-round flag: none
  ASSERT_EQ(bytes[bytes.size() - 9], 0u);   // the pairwise term flag: none
  bytes.erase(bytes.end() - 10, bytes.end() - 8);
  // Format 4's learner and class map, which format 2 does not have.
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(labelsEndOffset()),
              bytes.begin() + static_cast<std::ptrdiff_t>(featureSectionOffset()));
  const RandomForest loaded = loadAsFormat(bytes, 2);
  EXPECT_EQ(loaded.formatVersion(), 2u);
  EXPECT_EQ(loaded.dim(), kFeatureDim);
  EXPECT_EQ(loaded.contextRound(), nullptr);
  const TrainingSet probe = makeBlobs(5, 77, 2.0f);
  for (const auto& x : probe.features) {
    const auto a = forest_.predict(x);
    const auto b = loaded.predict(x);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof a), 0);
  }
  // A format-2 file cannot carry extra columns.
  auto more = bytes;
  putU32(more, kVersionOffset, 2);
  putU32(more, labelsEndOffset(), kFeatureDim + 1);
  fixChecksum(more);
  expectRefused(more, "15 features");
}

TEST_F(ForestFileCorruption, BadContextRoundFlag) {
  auto bytes = good_;
  ASSERT_GT(bytes.size(), 10u);
  bytes[bytes.size() - 10] = 2;
  fixChecksum(bytes);
  expectRefused(bytes, "context round flag = 2");
}

// Format 4 (issue 35, before the learned pairwise term): format 5 without the
// pairwise term flag. Such files (models/findmug.fmf 12292e1b) still load,
// without a term.
TEST_F(ForestFileCorruption, Format4FileLoadsWithoutPairwiseTerm) {
  auto bytes = good_;
  ASSERT_EQ(bytes[bytes.size() - 9], 0u);  // the pairwise term flag: none
  bytes.erase(bytes.end() - 9);
  const RandomForest loaded = loadAsFormat(bytes, 4);
  EXPECT_EQ(loaded.formatVersion(), 4u);
  EXPECT_EQ(loaded.pairwiseContext(), nullptr);
  EXPECT_EQ(loaded.trees().size(), forest_.trees().size());
  // A format-4 file that still has the flag byte has a byte too many.
  auto longer = good_;
  putU32(longer, kVersionOffset, 4);
  fixChecksum(longer);
  expectRefused(longer, "unexpected bytes");
}

// The pairwise term's bytes: the flag, then 14 float64 and a uint64 before the
// checksum. Each unusable value is refused naming the file and the field.
class PairwiseTermCorruption : public ::testing::Test {
 protected:
  void SetUp() override {
    ForestParams params;
    params.num_trees = 2;
    params.max_depth = 3;
    forest_ = RandomForest::train(makeBlobs(10, 12, 2.0f), params);
    forest_.setPairwiseContext(learnedLookingTerm());
    forest_.save(dir_.str("model.fmf"));
    good_ = readBytes(dir_.str("model.fmf"));
    term_ = good_.size() - kChecksumBytes - kTermBytes;
    ASSERT_EQ(good_[term_ - 1], 1u);  // the flag
  }
  // Offset of the term's k-th float64 (0 bias, 1-4 weights, 5-8 means,
  // 9-12 scales, 13 mean cost); 14 is the uint64 edge count.
  std::size_t field(int k) const { return term_ + 8 * static_cast<std::size_t>(k); }
  std::vector<std::uint8_t> withDouble(int k, double v) const {
    auto bytes = good_;
    std::uint64_t u = 0;
    std::memcpy(&u, &v, sizeof u);
    test::putU64(bytes, field(k), u);
    fixChecksum(bytes);
    return bytes;
  }
  void expectRefused(const std::vector<std::uint8_t>& bytes, const std::string& word) {
    test::expectModelRefused(dir_.str("bad.fmf"), bytes, word);
  }

  static constexpr std::size_t kChecksumBytes = 8;
  static constexpr std::size_t kTermBytes = 14 * 8 + 8;
  TempDir dir_;
  RandomForest forest_;
  std::vector<std::uint8_t> good_;
  std::size_t term_ = 0;
};

TEST_F(PairwiseTermCorruption, IntactTermLoads) {
  const RandomForest loaded = RandomForest::load(dir_.str("model.fmf"));
  ASSERT_NE(loaded.pairwiseContext(), nullptr);
  EXPECT_EQ(loaded.pairwiseContext()->training_edges, 133071u);
}

TEST_F(PairwiseTermCorruption, BadFlagAndValuesAreRefusedByName) {
  auto bytes = good_;
  bytes[term_ - 1] = 3;
  fixChecksum(bytes);
  expectRefused(bytes, "pairwise term flag = 3");
  expectRefused(withDouble(0, std::nan("")), "bias");
  expectRefused(withDouble(2, std::numeric_limits<double>::infinity()), "weight");
  expectRefused(withDouble(6, std::nan("")), "mean");
  expectRefused(withDouble(11, 0.0), "scale");
  expectRefused(withDouble(12, -1.0), "scale");
  expectRefused(withDouble(13, 0.0), "mean cost");
  bytes = good_;
  test::putU64(bytes, field(14), 0);
  fixChecksum(bytes);
  expectRefused(bytes, "training edge");
  // The term cut off before the checksum.
  bytes = good_;
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(field(13)),
              bytes.begin() + static_cast<std::ptrdiff_t>(field(14)));
  fixChecksum(bytes);
  expectRefused(bytes, "");
}

TEST_F(ForestFileCorruption, DifferentLabelNames) {
  auto bytes = good_;
  const auto it =
      std::search(bytes.begin(), bytes.end(), kLabelNames[5].begin(), kLabelNames[5].end());
  ASSERT_NE(it, bytes.end());
  *(it + 1) = 'X';  // "chair" -> "cXair"
  fixChecksum(bytes);
  expectRefused(bytes, "label names differ");

  bytes = good_;
  putU32(bytes, kLabelCountOffset, 9);
  fixChecksum(bytes);
  expectRefused(bytes, "9 labels");
}

TEST_F(ForestFileCorruption, DifferentFeatureLayout) {
  auto bytes = good_;
  const std::string_view name = kFeatureNames[6];
  const auto it = std::search(bytes.begin(), bytes.end(), name.begin(), name.end());
  ASSERT_NE(it, bytes.end());
  *it = 'X';
  fixChecksum(bytes);
  expectRefused(bytes, "feature layout differs");

  bytes = good_;
  putU32(bytes, featureSectionOffset(), 13);
  fixChecksum(bytes);
  expectRefused(bytes, "13 features");
}

TEST_F(ForestFileCorruption, AbsurdCounts) {
  auto bytes = good_;
  putU32(bytes, treeCountOffset(), 20000);
  fixChecksum(bytes);
  expectRefused(bytes, "num_trees");

  bytes = good_;
  putU32(bytes, paramsOffset(), 20000);  // params.num_trees
  fixChecksum(bytes);
  expectRefused(bytes, "num_trees");

  bytes = good_;
  putU32(bytes, treeCountOffset() + 4, 0xFFFFFFFFu);  // node count of tree 0
  fixChecksum(bytes);
  expectRefused(bytes, "node count");

  bytes = good_;
  putU32(bytes, paramsOffset() + 4, 1000);  // params.max_depth
  fixChecksum(bytes);
  expectRefused(bytes, "max_depth");
}

TEST_F(ForestFileCorruption, BadTreeStructure) {
  const auto nodes = nodeOffsetsOfFirstTree(good_);
  ASSERT_EQ(static_cast<std::int32_t>(getU32(good_, nodes[0])) >= 0, true) << "root should split";
  const std::size_t root_left = nodes[0] + 8;
  const std::size_t root_right = nodes[0] + 12;

  auto bytes = good_;
  putU32(bytes, root_left, static_cast<std::uint32_t>(nodes.size()));  // one past the end
  fixChecksum(bytes);
  expectRefused(bytes, "out of range");

  bytes = good_;
  putU32(bytes, root_left, 0);  // back to the root: a cycle
  fixChecksum(bytes);
  expectRefused(bytes, "out of range");

  bytes = good_;
  putU32(bytes, root_right, getU32(good_, root_left));  // both children the same node
  fixChecksum(bytes);
  expectRefused(bytes, "more than one parent");

  // An inner node below the root pointing at itself.
  const auto inner = std::find_if(nodes.begin() + 1, nodes.end(), [&](std::size_t off) {
    return static_cast<std::int32_t>(getU32(good_, off)) >= 0;
  });
  ASSERT_NE(inner, nodes.end()) << "tree 0 should have a second inner node";
  bytes = good_;
  putU32(bytes, *inner + 8, static_cast<std::uint32_t>(inner - nodes.begin()));
  fixChecksum(bytes);
  expectRefused(bytes, "cycle");

  bytes = good_;
  putU32(bytes, nodes[0], 14);  // feature index out of range
  fixChecksum(bytes);
  expectRefused(bytes, "feature index 14");

  const auto leaf = std::find_if(nodes.begin(), nodes.end(), [&](std::size_t off) {
    return static_cast<std::int32_t>(getU32(good_, off)) < 0;
  });
  bytes = good_;
  putU32(bytes, *leaf + 4, 0x7fc00000u);  // NaN probability
  fixChecksum(bytes);
  expectRefused(bytes, "leaf probability");
}

}  // namespace
}  // namespace findmug
