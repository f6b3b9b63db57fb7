// findmug/forest.hpp — randomized decision forest (Criminisi et al. style).
//
// Axis-aligned splits chosen among random (feature, threshold) candidates by
// information gain; leaves hold label histograms; p(y|x) is the mean of the
// reached leaves' distributions. Training is seeded and reproducible: tree t
// uses seed + t whatever the number of threads.
//
// Feature rows: every forest reads the 14 base features of features.hpp
// first, optionally followed by extra columns (region features, context
// features; see context_features.hpp). The column names are part of the
// model, so a model is never fed columns it was not trained on. A model may
// carry a second, auto-context stage: a forest whose rows are the first
// stage's rows followed by the first stage's class distributions aggregated
// over 3-D neighbourhoods.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
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
  int candidate_features = 4;     // random features tried per node (<= feature count)
  int candidate_thresholds = 10;  // random thresholds tried per feature
  bool class_weighting = true;    // weight samples by inverse class frequency
  double bagging_fraction = 1.0;  // share of samples (with replacement) per tree;
                                  // 1.0 = every tree sees all samples, no bootstrap
  std::uint64_t seed = 42;
  int num_threads = 0;            // 0 = hardware concurrency; not part of the model
                                  // (not saved: the model does not depend on it)
};

struct TrainingSet {
  std::vector<FeatureVector> features;  // the 14 base features per sample
  // Optional extra columns after the base features: their names, and the
  // values row-major (extra_names.size() per sample, same order as features).
  std::vector<std::string> extra_names;
  std::vector<float> extra;
  std::vector<std::uint8_t> labels;  // 0..kNumLabels-1 (no void)
  std::vector<float> weights;        // optional, empty = 1 each (e.g. patch pixel count)
  // Optional finer classes, used only to choose splits (training.split_labels):
  // the gain is measured over split_labels (0..split_classes-1) while leaves
  // hold distributions over `labels`, so the model stays an 8-class model.
  // Empty = split on `labels`.
  std::vector<std::uint8_t> split_labels;
  int split_classes = 0;
};

// The most split classes a training set may have (NYU-40 plus headroom).
inline constexpr int kMaxSplitClasses = 64;

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

  // Throws findmug::Error on an empty forest or a row whose length is not
  // dim(). Non-finite features go right. The FeatureVector overload is for
  // forests of the 14 base features only.
  ClassProbabilities predict(std::span<const float> row) const;
  ClassProbabilities predict(const FeatureVector& x) const {
    return predict(std::span<const float>(x.data(), x.size()));
  }

  // Column names of the rows this forest reads (kFeatureNames, then extras).
  const std::vector<std::string>& featureNames() const { return feature_names_; }
  int dim() const { return static_cast<int>(feature_names_.size()); }

  // The auto-context stage (null when the model has none). Its rows are this
  // forest's rows followed by context columns. Setting it changes id().
  void setContextStage(RandomForest stage);
  const RandomForest* contextStage() const { return context_stage_.get(); }
  // Model file format the forest was loaded from (0 when trained in-process).
  std::uint32_t formatVersion() const { return format_version_; }

  // Versioned binary model: magic, format version, label names, feature
  // layout, parameters, trees, optional context stage, checksum. Format 3 is
  // written; format 2 (14 base features, no context stage) is still read. `load` refuses a truncated,
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
  void updateId();

  ForestParams params_;
  std::vector<Tree> trees_;
  std::vector<std::string> feature_names_;
  std::shared_ptr<const RandomForest> context_stage_;
  std::uint32_t format_version_ = 0;
  Settings extraction_settings_;
  std::string id_;
  std::string source_;
};

}  // namespace findmug
