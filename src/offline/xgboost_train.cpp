// xgboost_train.cpp — RandomForest::trainBoosted: gradient-boosted trees trained
// through XGBoost's C API (multi:softprob over the internal classes, samples
// weighted like the forest's). Built into findmug_offline, not the core: the daemon
// and the package never train. The model comes back through the same bytes -> handle
// path as a loaded one (learner/xgboost_learner.hpp), so it predicts the same bits
// before and after a save. Training runs on learner.num_threads threads.
#include <xgboost/c_api.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "findmug/common/error.hpp"
#include "learner/xgboost_learner.hpp"

namespace findmug {

namespace {

using xgboost_learner::check;
using xgboost_learner::number;

// Owns a handle for the length of a call.
struct DMatrixGuard {
  DMatrixHandle handle = nullptr;
  ~DMatrixGuard() {
    if (handle) XGDMatrixFree(handle);
  }
};
struct BoosterGuard {
  BoosterHandle handle = nullptr;
  ~BoosterGuard() {
    if (handle) XGBoosterFree(handle);
  }
};

}  // namespace

RandomForest RandomForest::trainBoosted(const TrainingSet& data, const InternalClasses& classes,
                                        const XGBoostParams& params, bool class_weighting,
                                        int num_threads) {
  const std::string where = "xgboost training";
  xgboost_learner::validateParams(params, where);
  xgboost_learner::quietXGBoost();
  const std::size_t n = data.features.size();
  if (n == 0) throw Error(where + ": the training set is empty");
  const bool internal = classes.scheme != "labels";
  if (internal != !data.split_labels.empty())
    throw Error(where + ": internal classes '" + classes.scheme + "' need " +
                (internal ? "the internal class of every sample" : "no split labels"));
  const int k = classes.count();
  const std::vector<std::uint8_t>& ids = internal ? data.split_labels : data.labels;
  if (ids.size() != n || data.extra.size() != n * data.extra_names.size() ||
      (!data.weights.empty() && data.weights.size() != n))
    throw Error(where + ": the training set's columns have different lengths");
  const std::size_t extra_dim = data.extra_names.size();
  const std::size_t dim = kFeatureDim + extra_dim;

  std::vector<float> rows(n * dim);
  std::vector<float> labels(n), weights(n);
  std::vector<double> class_total(static_cast<std::size_t>(k), 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (ids[i] >= k)
      throw Error(where + ": sample " + std::to_string(i) + " has class " +
                  std::to_string(ids[i]) + " (expected 0.." + std::to_string(k - 1) + ")");
    float* row = rows.data() + i * dim;
    std::copy(data.features[i].begin(), data.features[i].end(), row);
    std::copy_n(data.extra.begin() + static_cast<std::ptrdiff_t>(i * extra_dim), extra_dim,
                row + kFeatureDim);
    for (std::size_t f = 0; f < dim; ++f)
      if (!std::isfinite(row[f]))
        throw Error(where + ": sample " + std::to_string(i) + " column " + std::to_string(f) +
                    " is not finite");
    labels[i] = static_cast<float>(ids[i]);
    weights[i] = data.weights.empty() ? 1.0f : data.weights[i];
  }
  // The classes weighting balances: the internal ones (weight_by_split_labels)
  // or the labels, as the forest does.
  const std::vector<std::uint8_t>& balanced =
      internal && data.weight_by_split_labels ? data.split_labels : data.labels;
  for (std::size_t i = 0; i < n; ++i) {
    if (balanced[i] >= class_total.size()) class_total.resize(balanced[i] + 1u, 0.0);
    class_total[balanced[i]] += weights[i];
  }
  if (class_weighting) {
    // The forest's inverse class frequency: every present class carries the same total weight.
    double total = 0.0;
    int present = 0;
    for (double c : class_total) {
      total += c;
      present += c > 0.0;
    }
    for (std::size_t i = 0; i < n; ++i)
      weights[i] = static_cast<float>(weights[i] * (total / (present * class_total[balanced[i]])));
  }

  DMatrixGuard dtrain;
  check(XGDMatrixCreateFromMat(rows.data(), static_cast<bst_ulong>(n), static_cast<bst_ulong>(dim),
                               std::numeric_limits<float>::quiet_NaN(), &dtrain.handle),
        where, "training matrix");
  check(XGDMatrixSetFloatInfo(dtrain.handle, "label", labels.data(), static_cast<bst_ulong>(n)),
        where, "labels");
  check(XGDMatrixSetFloatInfo(dtrain.handle, "weight", weights.data(), static_cast<bst_ulong>(n)),
        where, "weights");
  BoosterGuard booster;
  check(XGBoosterCreate(&dtrain.handle, 1, &booster.handle), where, "booster creation");
  const std::pair<const char*, std::string> settings[] = {
      {"objective", "multi:softprob"},
      {"num_class", std::to_string(k)},
      {"tree_method", "hist"},
      {"max_depth", std::to_string(params.max_depth)},
      {"eta", number(params.eta)},
      {"subsample", number(params.subsample)},
      {"colsample_bytree", number(params.colsample)},
      {"min_child_weight", number(params.min_child_weight)},
      {"lambda", number(params.lambda)},
      {"seed", std::to_string(params.seed)},
      {"nthread", std::to_string(num_threads)},
      {"verbosity", "0"},
  };
  for (const auto& [key, value] : settings)
    check(XGBoosterSetParam(booster.handle, key, value.c_str()), where, key);
  for (int round = 0; round < params.rounds; ++round)
    check(XGBoosterUpdateOneIter(booster.handle, round, dtrain.handle), where, "boosting round");
  bst_ulong length = 0;
  const char* bytes = nullptr;
  check(XGBoosterSaveModelToBuffer(booster.handle, "{\"format\": \"ubj\"}", &length, &bytes), where,
        "model save");
  std::vector<std::uint8_t> blob(reinterpret_cast<const std::uint8_t*>(bytes),
                                 reinterpret_cast<const std::uint8_t*>(bytes) + length);

  RandomForest model;
  for (auto name : kFeatureNames) model.feature_names_.emplace_back(name);
  for (const auto& name : data.extra_names) model.feature_names_.push_back(name);
  model.xgboost_params_ = params;
  model.params_.class_weighting = class_weighting;
  model.internal_classes_ = classes;
  model.booster_ = Booster::fromBlob(std::move(blob), k, static_cast<int>(dim), where);
  model.updateId();
  return model;
}

}  // namespace findmug
