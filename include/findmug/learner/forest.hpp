// findmug/learner/forest.hpp — randomized decision forest (Criminisi et al. style).
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
// carry a second, auto-context round: a forest whose rows are the first
// round's rows followed by the first round's class distributions aggregated
// over 3-D neighbourhoods.
//
// Learners (learner.kind): the model is this forest (the paper's, the
// default) or gradient-boosted trees (XGBoost, src/xgboost_learner.*), behind
// the same type, file and prediction calls. Classes (learner.classes): a model
// may be trained on finer internal classes (NYU-13 or NYU-40 classes, each
// split by the findmug label its pixels carry, so every internal class is
// pure) and merges its posterior into the 8 labels; the internal class names
// and their merge map are part of the model (format 4). A model may also carry
// the learned pairwise term of mrf.pairwise = context (format 5).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "findmug/features/features.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/mrf/context_pairwise.hpp"

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
  // Hierarchical shrinkage of the leaves' distributions towards their
  // ancestors' (lambda; 0 = off, the paper's leaves): each step down the path
  // counts 1 / (1 + lambda / N) with N the parent's sample count. Applied when
  // the leaves are made, so a model's file holds the shrunk distributions and
  // prediction does not read it (not saved, as num_threads).
  double shrinkage = 0.0;
  std::uint64_t seed = 42;
  int num_threads = 0;            // 0 = hardware concurrency; not part of the model
                                  // (not saved: the model does not depend on it)
};

// The learner behind a model (learner.kind).
enum class LearnerKind : std::uint8_t { Forest = 0, XGBoost = 1 };
const char* learnerKindName(LearnerKind kind);  // "forest", "xgboost"

// Gradient-boosted trees (learner.kind = xgboost; xgboost.* settings).
struct XGBoostParams {
  int rounds = 60;               // boosting rounds (trees per class)
  int max_depth = 6;
  double eta = 0.3;              // learning rate
  double subsample = 1.0;        // share of rows per round
  double colsample = 1.0;        // share of columns per tree
  double min_child_weight = 1.0;
  double lambda = 1.0;           // L2 regularisation of leaf weights
  int seed = 42;
};

// The classes a model is trained on and how they merge into the 8 labels.
// scheme "labels": the 8 labels themselves (names = kLabelNames, identity
// map). "nyu13" / "nyu40": each internal class is a (fine class, label) pair
// present in the training set, named "label/fine" (e.g. "unknown/furniture").
struct InternalClasses {
  std::string scheme = "labels";
  std::vector<std::string> names;
  std::vector<std::uint8_t> to_label;  // per internal class, its findmug label
  int count() const { return static_cast<int>(names.size()); }
  bool operator==(const InternalClasses&) const = default;
};
InternalClasses labelClasses();  // scheme "labels"
// The most internal classes a model may have (NYU-40 pairs plus headroom).
inline constexpr int kMaxInternalClasses = 64;

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
  // Internal classes (learner.classes): split_labels then hold the internal
  // class of each sample, and class weighting (learner.class_weighting) is by
  // internal class frequency rather than label frequency. The forest stores
  // its leaves merged into the 8 labels (for an averaging forest the same
  // answer as merging the averaged fine posterior); the booster learns the
  // internal classes and merges its posterior at prediction.
  bool weight_by_split_labels = false;
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
  // `n` rows of dim() values each, row-major, into out[0..n): the same
  // answers as predict() row by row (a booster predicts them in one call).
  void predictRows(std::span<const float> rows, std::size_t n,
                   std::span<ClassProbabilities> out) const;

  // The learner and the classes the model was trained on. A booster model
  // holds no trees of its own (trees() is empty).
  LearnerKind learnerKind() const { return booster_ ? LearnerKind::XGBoost : LearnerKind::Forest; }
  const InternalClasses& internalClasses() const { return internal_classes_; }
  // Records the internal classes a forest was trained on (checked: names,
  // labels, count); changes id().
  void setInternalClasses(InternalClasses classes);
  // One line for logs: "forest of 8 trees, 8 classes (labels)", "xgboost of
  // 100 rounds, 17 internal classes (nyu13)", with ", learned pairwise term"
  // when the model carries one.
  std::string summary() const;
  // The booster's parameters (meaningful when learnerKind() is XGBoost).
  const XGBoostParams& xgboostParams() const { return xgboost_params_; }
  // A model of gradient-boosted trees trained on `data` (its split_labels are
  // the internal classes when `classes` is not the 8 labels), weighted like
  // the forest (`class_weighting`). Refuses a set the booster cannot learn.
  static RandomForest trainBoosted(const TrainingSet& data, const InternalClasses& classes,
                                   const XGBoostParams& params, bool class_weighting,
                                   int num_threads);

  // Column names of the rows this forest reads (kFeatureNames, then extras).
  const std::vector<std::string>& featureNames() const { return feature_names_; }
  int dim() const { return static_cast<int>(feature_names_.size()); }

  // The auto-context round (null when the model has none). Its rows are this
  // forest's rows followed by context columns. Setting it changes id().
  void setContextRound(RandomForest round);
  const RandomForest* contextRound() const { return context_round_.get(); }
  // The learned pairwise term of mrf.pairwise = context (context_pairwise.hpp):
  // learned from the same training frames, so it travels with the model
  // (format 5). Null when the model has none. Checked
  // (validatePairwiseContext); setting it changes id().
  void setPairwiseContext(std::optional<PairwiseContext> term);
  const PairwiseContext* pairwiseContext() const {
    return pairwise_context_ ? &*pairwise_context_ : nullptr;
  }
  // Model file format the forest was loaded from (0 when trained in-process).
  std::uint32_t formatVersion() const { return format_version_; }

  // Versioned binary model: magic, format version, label names, learner and
  // internal classes (format 4), feature layout, parameters, trees or booster,
  // optional context round, optional learned pairwise term (format 5),
  // checksum. Format 5 is written; formats 4 (no pairwise term), 3 (also: a
  // forest on the 8 labels) and 2 (also: 14 base features, no context round)
  // are still read. `load` refuses a truncated, corrupt or wrong-version file with
  // a findmug::Error naming the file and the problem.
  void save(const std::string& path) const;
  static RandomForest load(const std::string& path);

  // Settings of the feature extraction the forest was trained with (cloud.*,
  // normals.*, oversegmentation.* as "key" -> "value"), stored in the model file so
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
  bool empty() const { return trees_.empty() && !booster_; }

  // The XGBoost model (src/learner/xgboost_learner.hpp); null for a forest.
  struct Booster;
  const Booster* booster() const { return booster_.get(); }

 private:
  void updateId();

  ForestParams params_;
  std::vector<Tree> trees_;
  std::vector<std::string> feature_names_;
  std::shared_ptr<const RandomForest> context_round_;
  std::optional<PairwiseContext> pairwise_context_;
  std::uint32_t format_version_ = 0;
  Settings extraction_settings_;
  std::string id_;
  std::string source_;
  InternalClasses internal_classes_ = labelClasses();
  XGBoostParams xgboost_params_;
  std::shared_ptr<const Booster> booster_;
};

}  // namespace findmug
