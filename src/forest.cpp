// forest.cpp — RandomForest's model-independent parts: prediction, the
// context stage and extraction settings, the model id, and the parameter
// check. Training is in forest_train.cpp, the model file in forest_format.cpp.
#include "findmug/forest.hpp"

#include <algorithm>
#include <array>

#include "findmug/error.hpp"
#include "forest_format.hpp"

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
  if (p.candidate_features < 1 || p.candidate_features > static_cast<int>(kMaxFeatures))
    fail("candidate_features", std::to_string(p.candidate_features),
         "expected 1.." + std::to_string(kMaxFeatures));
  if (p.candidate_thresholds < 1 || p.candidate_thresholds > 100000)
    fail("candidate_thresholds", std::to_string(p.candidate_thresholds), "expected 1..100000");
  if (!(p.bagging_fraction > 0.0 && p.bagging_fraction <= 1.0))
    fail("bagging_fraction", std::to_string(p.bagging_fraction), "expected in (0, 1]");
  if (p.num_threads < 0) fail("num_threads", std::to_string(p.num_threads), "expected >= 0");
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

void RandomForest::setContextStage(RandomForest stage) {
  if (stage.empty()) throw Error("RandomForest: the context stage is empty (not trained)");
  if (stage.contextStage())
    throw Error("RandomForest: a context stage cannot have a context stage of its own");
  const auto& names = stage.featureNames();
  if (names.size() <= feature_names_.size() ||
      !std::equal(feature_names_.begin(), feature_names_.end(), names.begin()))
    throw Error("RandomForest: the context stage's rows must start with the first stage's " +
                std::to_string(feature_names_.size()) + " columns and add context columns");
  context_stage_ = std::make_shared<const RandomForest>(std::move(stage));
  updateId();
}

void RandomForest::updateId() {
  // The id names the model's content: settings and context stage included.
  const auto bytes = serialize(*this);
  std::uint64_t checksum = 0;
  for (std::size_t i = 0; i < kChecksumSize; ++i)
    checksum |= static_cast<std::uint64_t>(bytes[bytes.size() - kChecksumSize + i]) << (8 * i);
  id_ = idFromChecksum(checksum);
}

ClassProbabilities RandomForest::predict(std::span<const float> x) const {
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
