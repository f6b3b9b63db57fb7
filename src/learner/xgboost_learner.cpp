// xgboost_learner.cpp — RandomForest::trainBoosted and the Booster: training
// gradient-boosted trees through XGBoost's C API (multi:softprob over the
// internal classes, samples weighted like the forest's), and predicting with
// a loaded booster on one thread.
//
// Determinism: prediction runs with nthread = 1 on dense float rows, and the
// model the trainer returns is the one its bytes load into, so eval, the
// daemon and a reloaded file give the same bits. Training runs on
// learner.num_threads threads (offline only: findmug-train, findmug-eval).
#include "learner/xgboost_learner.hpp"

#include <xgboost/c_api.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

#include "findmug/common/error.hpp"

namespace findmug {

namespace {

void check(int rc, const std::string& where, const char* what) {
  if (rc != 0)
    throw Error(where + ": xgboost " + what + " failed: " + std::string(XGBGetLastError()));
}

// XGBoost logs warnings on its own (to stderr) unless told not to; once per process.
void quietXGBoost() {
  static const bool done = [] {
    XGBSetGlobalConfig("{\"verbosity\": 0}");
    return true;
  }();
  (void)done;
}

std::string number(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

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

void xgboost_learner::validateParams(const XGBoostParams& p, const std::string& where) {
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rule) {
    throw Error(where + ": xgboost parameter " + field + " = " + value + " is invalid (" + rule +
                ")");
  };
  if (p.rounds < 1 || p.rounds > kMaxRounds)
    fail("rounds", std::to_string(p.rounds), "expected 1.." + std::to_string(kMaxRounds));
  if (p.max_depth < 1 || p.max_depth > kMaxDepth)
    fail("max_depth", std::to_string(p.max_depth), "expected 1.." + std::to_string(kMaxDepth));
  if (!(p.eta > 0.0 && p.eta <= 1.0)) fail("eta", number(p.eta), "expected in (0, 1]");
  if (!(p.subsample > 0.0 && p.subsample <= 1.0))
    fail("subsample", number(p.subsample), "expected in (0, 1]");
  if (!(p.colsample > 0.0 && p.colsample <= 1.0))
    fail("colsample", number(p.colsample), "expected in (0, 1]");
  if (!(p.min_child_weight >= 0.0 && p.min_child_weight <= 1e6))
    fail("min_child_weight", number(p.min_child_weight), "expected 0..1e6");
  if (!(p.lambda >= 0.0 && p.lambda <= 1e6)) fail("lambda", number(p.lambda), "expected 0..1e6");
  if (p.seed < 0) fail("seed", std::to_string(p.seed), "expected >= 0");
}

RandomForest::Booster::~Booster() {
  if (handle) XGBoosterFree(static_cast<BoosterHandle>(handle));
}

std::shared_ptr<const RandomForest::Booster> RandomForest::Booster::fromBlob(
    std::vector<std::uint8_t> blob, int num_classes, int dim, const std::string& where) {
  quietXGBoost();
  if (blob.empty()) throw Error(where + ": the xgboost booster is empty (0 bytes)");
  if (num_classes < 1 || num_classes > kMaxInternalClasses || dim < 1)
    throw Error(where + ": xgboost booster with " + std::to_string(num_classes) +
                " classes and " + std::to_string(dim) + " columns");
  auto booster = std::make_shared<Booster>();
  BoosterHandle handle = nullptr;
  check(XGBoosterCreate(nullptr, 0, &handle), where, "booster creation");
  booster->handle = handle;
  const std::string what = where + ": xgboost booster (" + std::to_string(blob.size()) + " bytes)";
  check(XGBoosterLoadModelFromBuffer(handle, blob.data(), static_cast<bst_ulong>(blob.size())),
        what, "model load (booster blob truncated or corrupt)");
  check(XGBoosterSetParam(handle, "nthread", "1"), where, "nthread");
  bst_ulong features = 0;
  check(XGBoosterGetNumFeature(handle, &features), where, "feature count");
  if (features != static_cast<bst_ulong>(dim))
    throw Error(where + ": the xgboost booster reads " + std::to_string(features) +
                " columns but the model names " + std::to_string(dim));
  int rounds = 0;
  check(XGBoosterBoostedRounds(handle, &rounds), where, "round count");
  if (rounds < 1) throw Error(where + ": the xgboost booster has no boosted rounds");
  booster->blob = std::move(blob);
  booster->dim = dim;
  // The output width is the booster's class count: ask it with one row.
  const std::vector<float> zeros(static_cast<std::size_t>(dim), 0.0f);
  const std::string config =
      "{\"type\": 0, \"training\": false, \"iteration_begin\": 0, \"iteration_end\": 0, "
      "\"strict_shape\": true, \"missing\": NaN, \"cache_id\": 0}";
  const std::string values = "{\"data\": [" +
                             std::to_string(reinterpret_cast<std::uintptr_t>(zeros.data())) +
                             ", true], \"shape\": [1, " + std::to_string(dim) +
                             "], \"typestr\": \"<f4\", \"version\": 3}";
  const bst_ulong* shape = nullptr;
  bst_ulong ndim = 0;
  const float* result = nullptr;
  check(XGBoosterPredictFromDense(handle, values.c_str(), config.c_str(), nullptr, &shape, &ndim,
                                  &result),
        where, "prediction");
  const bst_ulong width = ndim >= 2 ? shape[ndim - 1] : 1;
  if (width != static_cast<bst_ulong>(num_classes))
    throw Error(where + ": the xgboost booster answers " + std::to_string(width) +
                " classes but the model's class map has " + std::to_string(num_classes) +
                " (class count mismatch)");
  booster->num_classes = num_classes;
  return booster;
}

void RandomForest::Booster::predict(const float* rows, std::size_t n, float* out) const {
  if (n == 0) return;
  const std::string config =
      "{\"type\": 0, \"training\": false, \"iteration_begin\": 0, \"iteration_end\": 0, "
      "\"strict_shape\": true, \"missing\": NaN, \"cache_id\": 0}";
  const std::string values =
      "{\"data\": [" + std::to_string(reinterpret_cast<std::uintptr_t>(rows)) +
      ", true], \"shape\": [" + std::to_string(n) + ", " + std::to_string(dim) +
      "], \"typestr\": \"<f4\", \"version\": 3}";
  std::lock_guard lock(mutex);
  const bst_ulong* shape = nullptr;
  bst_ulong ndim = 0;
  const float* result = nullptr;
  check(XGBoosterPredictFromDense(static_cast<BoosterHandle>(handle), values.c_str(),
                                  config.c_str(), nullptr, &shape, &ndim, &result),
        "RandomForest::predict", "prediction");
  bst_ulong total = 1;
  for (bst_ulong d = 0; d < ndim; ++d) total *= shape[d];
  const std::size_t expected = n * static_cast<std::size_t>(num_classes);
  if (total != expected)
    throw Error("RandomForest::predict: the xgboost booster gave " + std::to_string(total) +
                " values for " + std::to_string(n) + " rows of " + std::to_string(num_classes) +
                " classes");
  std::copy(result, result + expected, out);
}

RandomForest RandomForest::trainBoosted(const TrainingSet& data, const InternalClasses& classes,
                                        const XGBoostParams& params, bool class_weighting,
                                        int num_threads) {
  const std::string where = "xgboost training";
  xgboost_learner::validateParams(params, where);
  quietXGBoost();
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
