// forest.cpp — RandomForest's model-independent parts: prediction, the
// context round and extraction settings, the model id, and the parameter
// check. Training is in forest_train.cpp, the model file in forest_format.cpp.
#include "findmug/learner/forest.hpp"

#include <algorithm>
#include <array>

#include "findmug/common/error.hpp"
#include "learner/forest_format.hpp"
#include "learner/xgboost_learner.hpp"

namespace findmug {

using namespace forest_format;

void forest_format::validateParams(const ForestParams& p, const std::string& where) {
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rule) {
    throw Error(where + ": forest parameter " + field + " = " + value + " is invalid (" + rule +
                ")");
  };
  if (p.num_trees < 1 || p.num_trees > kMaxTrees)
    fail("num_trees", std::to_string(p.num_trees), "expected 1.." + std::to_string(kMaxTrees));
  if (p.max_depth < 0 || p.max_depth > kMaxDepth)
    fail("max_depth", std::to_string(p.max_depth), "expected 0.." + std::to_string(kMaxDepth));
  if (p.min_samples_leaf < 1)
    fail("min_samples_leaf", std::to_string(p.min_samples_leaf), "expected >= 1");
  if (!(p.shrinkage >= 0.0 && p.shrinkage <= 1e6))
    fail("shrinkage", std::to_string(p.shrinkage), "expected 0 .. 1e6");
  if (p.candidate_features < 1 || p.candidate_features > static_cast<int>(kMaxFeatures))
    fail("candidate_features", std::to_string(p.candidate_features),
         "expected 1.." + std::to_string(kMaxFeatures));
  if (p.candidate_thresholds < 1 || p.candidate_thresholds > 100000)
    fail("candidate_thresholds", std::to_string(p.candidate_thresholds), "expected 1..100000");
  if (!(p.bagging_fraction > 0.0 && p.bagging_fraction <= 1.0))
    fail("bagging_fraction", std::to_string(p.bagging_fraction), "expected in (0, 1]");
  if (p.num_threads < 0) fail("num_threads", std::to_string(p.num_threads), "expected >= 0");
}

const char* learnerKindName(LearnerKind kind) {
  return kind == LearnerKind::XGBoost ? "xgboost" : "forest";
}

InternalClasses labelClasses() {
  InternalClasses out;
  out.scheme = "labels";
  for (int c = 0; c < kNumLabels; ++c) {
    out.names.emplace_back(kLabelNames[c]);
    out.to_label.push_back(static_cast<std::uint8_t>(c));
  }
  return out;
}

void forest_format::validateInternalClasses(const InternalClasses& classes,
                                            const std::string& where) {
  const std::string what = where + ": bad class map (learner.classes '" + classes.scheme + "'): ";
  if (classes.scheme != "labels" && classes.scheme != "nyu13" && classes.scheme != "nyu40")
    throw Error(what + "unknown scheme (expected labels, nyu13 or nyu40)");
  const int k = classes.count();
  if (k < 1 || k > kMaxInternalClasses)
    throw Error(what + std::to_string(k) + " internal classes (expected 1.." +
                std::to_string(kMaxInternalClasses) + ")");
  if (classes.to_label.size() != classes.names.size())
    throw Error(what + std::to_string(k) + " class names but " +
                std::to_string(classes.to_label.size()) + " merge entries (class count mismatch)");
  if (classes.scheme == "labels" && !(classes == labelClasses()))
    throw Error(what + "the scheme 'labels' must be the " + std::to_string(kNumLabels) +
                " labels in order, each merged into itself");
  for (int c = 0; c < k; ++c) {
    const auto& name = classes.names[static_cast<std::size_t>(c)];
    if (name.empty() || name.size() > kMaxNameLength)
      throw Error(what + "internal class " + std::to_string(c) + " has an empty or too long name");
    if (classes.to_label[static_cast<std::size_t>(c)] >= kNumLabels)
      throw Error(what + "internal class " + std::to_string(c) + " '" + name +
                  "' merges into label " +
                  std::to_string(classes.to_label[static_cast<std::size_t>(c)]) +
                  " (expected 0.." + std::to_string(kNumLabels - 1) + ")");
    for (int d = 0; d < c; ++d)
      if (classes.names[static_cast<std::size_t>(d)] == name)
        throw Error(what + "internal class name '" + name + "' appears twice");
  }
}

void RandomForest::setInternalClasses(InternalClasses classes) {
  if (booster_)
    throw Error("RandomForest: a booster's internal classes are fixed when it is trained");
  validateInternalClasses(classes, "RandomForest");
  internal_classes_ = std::move(classes);
  updateId();
}

std::string RandomForest::summary() const {
  const std::string classes = std::to_string(internal_classes_.count()) +
                              (internal_classes_.scheme == "labels" ? " classes (" : " internal classes (") +
                              internal_classes_.scheme + ")";
  const std::string pairwise = pairwise_context_ ? ", learned pairwise term" : "";
  if (booster_)
    return "xgboost of " + std::to_string(xgboost_params_.rounds) + " rounds, " + classes +
           pairwise;
  return "forest of " + std::to_string(trees_.size()) + " trees, " + classes + pairwise;
}

void RandomForest::setExtractionSettings(Settings settings) {
  if (settings.size() > kMaxSettings)
    throw Error("RandomForest: " + std::to_string(settings.size()) +
                " extraction settings (at most " + std::to_string(kMaxSettings) + ")");
  for (const auto& [key, value] : settings) {
    if (key.empty() || key.size() > kMaxNameLength || value.size() > kMaxNameLength)
      throw Error("RandomForest: extraction setting '" + key +
                  "' has an empty or too long name/value");
  }
  extraction_settings_ = std::move(settings);
  updateId();
}

void RandomForest::setContextRound(RandomForest round) {
  if (round.empty()) throw Error("RandomForest: the context round is empty (not trained)");
  if (round.contextRound())
    throw Error("RandomForest: a context round cannot have a context round of its own");
  const auto& names = round.featureNames();
  if (names.size() <= feature_names_.size() ||
      !std::equal(feature_names_.begin(), feature_names_.end(), names.begin()))
    throw Error("RandomForest: the context round's rows must start with the first round's " +
                std::to_string(feature_names_.size()) + " columns and add context columns");
  context_round_ = std::make_shared<const RandomForest>(std::move(round));
  updateId();
}

void RandomForest::setPairwiseContext(std::optional<PairwiseContext> term) {
  if (term) validatePairwiseContext(*term, "RandomForest");
  pairwise_context_ = std::move(term);
  updateId();
}

void RandomForest::updateId() {
  // The id names the model's content: settings and context round included.
  const auto bytes = serialize(*this);
  std::uint64_t checksum = 0;
  for (std::size_t i = 0; i < kChecksumSize; ++i)
    checksum |= static_cast<std::uint64_t>(bytes[bytes.size() - kChecksumSize + i]) << (8 * i);
  id_ = idFromChecksum(checksum);
}

void RandomForest::predictRows(std::span<const float> rows, std::size_t n,
                               std::span<ClassProbabilities> out) const {
  const auto dim = feature_names_.size();
  if (rows.size() != n * dim || out.size() < n)
    throw Error("RandomForest::predictRows: " + std::to_string(rows.size()) + " values for " +
                std::to_string(n) + " rows of " + std::to_string(dim) + " features");
  if (!booster_) {
    for (std::size_t i = 0; i < n; ++i) out[i] = predict(rows.subspan(i * dim, dim));
    return;
  }
  // The booster answers per internal class; each adds into its label.
  thread_local std::vector<float> fine;
  const auto k = static_cast<std::size_t>(booster_->num_classes);
  fine.resize(n * k);
  booster_->predict(rows.data(), n, fine.data());
  const auto& to_label = internal_classes_.to_label;
  for (std::size_t i = 0; i < n; ++i) {
    ClassProbabilities p{};
    const float* row = fine.data() + i * k;
    for (std::size_t c = 0; c < k; ++c) p[to_label[c]] += row[c];
    out[i] = p;
  }
}

ClassProbabilities RandomForest::predict(std::span<const float> x) const {
  if (booster_) {
    if (x.size() != feature_names_.size())
      throw Error("RandomForest::predict: a row of " + std::to_string(x.size()) +
                  " features for a model of " + std::to_string(feature_names_.size()));
    ClassProbabilities out{};
    predictRows(x, 1, {&out, 1});
    return out;
  }
  if (trees_.empty())
    throw Error("RandomForest::predict: the forest is empty (not trained/loaded)");
  if (x.size() != feature_names_.size())
    throw Error("RandomForest::predict: a row of " + std::to_string(x.size()) +
                " features for a forest of " + std::to_string(feature_names_.size()));
  std::array<float, kNumLabels> sum{};
  for (const Tree& tree : trees_) {
    const Node* nodes = tree.data();
    std::int32_t i = 0;
    while (nodes[i].feature >= 0)
      i = x[nodes[i].feature] < nodes[i].threshold ? nodes[i].left : nodes[i].right;
    const auto& d = nodes[i].distribution;
    for (int c = 0; c < kNumLabels; ++c) sum[c] += d[c];
  }
  const float inv = 1.0f / static_cast<float>(trees_.size());
  for (float& p : sum) p *= inv;
  return sum;
}

}  // namespace findmug
