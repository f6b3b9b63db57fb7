// xgboost_learner.cpp — the Booster: a loaded booster predicting on one thread
// through XGBoost's C API. Training (RandomForest::trainBoosted) is
// src/offline/xgboost_train.cpp, outside the core.
//
// Determinism: prediction runs with nthread = 1 on dense float rows, and the
// model the trainer returns is the one its bytes load into, so eval, the
// daemon and a reloaded file give the same bits.
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

using xgboost_learner::check;
using xgboost_learner::number;
using xgboost_learner::quietXGBoost;

void xgboost_learner::check(int rc, const std::string& where, const char* what) {
  if (rc != 0)
    throw Error(where + ": xgboost " + what + " failed: " + std::string(XGBGetLastError()));
}

std::string xgboost_learner::number(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

void xgboost_learner::quietXGBoost() {
  static const bool done = [] {
    XGBSetGlobalConfig("{\"verbosity\": 0}");
    return true;
  }();
  (void)done;
}

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

}  // namespace findmug
