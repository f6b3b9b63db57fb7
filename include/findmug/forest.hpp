// findmug/forest.hpp — randomized decision forest (Criminisi et al. style).
//
// Axis-aligned splits chosen among random (feature, threshold) candidates by
// information gain; leaves hold label histograms; p(y|x) is the mean of the
// reached leaves' distributions. Training is seeded and reproducible: tree t
// uses seed + t whatever the number of threads.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "findmug/features.hpp"
#include "findmug/labels.hpp"

namespace findmug {

struct ForestParams {
  int num_trees = 8;
  int max_depth = 12;
  int min_samples_leaf = 5;
  int candidate_features = 4;     // random features tried per node
  int candidate_thresholds = 10;  // random thresholds tried per feature
  bool class_weighting = true;    // weight samples by inverse class frequency
  double bagging_fraction = 1.0;  // share of samples (with replacement) per tree;
                                  // 1.0 = every tree sees all samples, no bootstrap
  std::uint64_t seed = 42;
  int num_threads = 0;            // 0 = hardware concurrency; not part of the model
                                  // (not saved: the model does not depend on it)
};

struct TrainingSet {
  std::vector<FeatureVector> features;
  std::vector<std::uint8_t> labels;  // 0..kNumLabels-1 (no void)
  std::vector<float> weights;        // optional, empty = 1 each (e.g. patch pixel count)
};

class RandomForest {
 public:
  struct Node {
    // Inner node: feature >= 0, go left when x[feature] < threshold.
    // Leaf: feature = -1 and `distribution` is the label histogram (normalised).
    std::int32_t feature = -1;
    float threshold = 0.0f;
    std::int32_t left = -1, right = -1;
    ClassProbabilities distribution{};
  };
  using Tree = std::vector<Node>;  // node 0 is the root

  // Progress callback: trees finished so far, total.
  using Progress = std::function<void(int done, int total)>;

  static RandomForest train(const TrainingSet& data, const ForestParams& params,
                            const Progress& progress = {});

  // Throws findmug::Error on an empty forest. Non-finite features go right.
  ClassProbabilities predict(const FeatureVector& x) const;

  // Versioned binary model: magic, format version, label names, feature
  // layout, parameters, trees, checksum. `load` refuses a truncated,
  // corrupt or wrong-version file with a findmug::Error naming the file.
  void save(const std::string& path) const;
  static RandomForest load(const std::string& path);

  // Settings of the feature extraction the forest was trained with (cloud.*,
  // normals.*, overseg.* as "key" -> "value"), stored in the model file so
  // that a model is never run on features computed differently. Empty for
  // forests trained in-process without them. Setting them changes id().
  using Settings = std::vector<std::pair<std::string, std::string>>;
  void setExtractionSettings(Settings settings);
  const Settings& extractionSettings() const { return extraction_settings_; }
  // The file the forest was loaded from ("" when trained in-process).
  const std::string& source() const { return source_; }

  const ForestParams& params() const { return params_; }
  const std::vector<Tree>& trees() const { return trees_; }
  // Short stable id of the model (derived from the checksum), for status messages.
  std::string id() const { return id_; }
  bool empty() const { return trees_.empty(); }

 private:
  ForestParams params_;
  std::vector<Tree> trees_;
  Settings extraction_settings_;
  std::string id_;
  std::string source_;
};

}  // namespace findmug
