// xgboost_learner.hpp — internal to findmug_core (not installed): the
// gradient-boosted trees behind RandomForest when learner.kind = xgboost.
// The booster is kept as the bytes the model file stores (XGBoost's UBJSON
// model) and one loaded XGBoost handle, which predicts on one thread from
// dense rows. A trained booster goes through the same bytes -> handle path as
// a loaded one, so a model predicts the same bits before and after a save.
// No XGBoost header is included here: only xgboost_learner.cpp (prediction) and
// src/offline/xgboost_train.cpp (training, outside the core) see the C API.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "findmug/learner/forest.hpp"

namespace findmug {

struct RandomForest::Booster {
  std::vector<std::uint8_t> blob;  // the XGBoost model (UBJSON), as stored in the file
  int num_classes = 0;             // columns of the booster's output (internal classes)
  int dim = 0;                     // columns of its input rows
  void* handle = nullptr;          // BoosterHandle
  // XGBoost's prediction output buffer belongs to the handle: one call at a time.
  mutable std::mutex mutex;

  Booster() = default;
  Booster(const Booster&) = delete;
  Booster& operator=(const Booster&) = delete;
  ~Booster();

  // Loads `blob` and checks that the booster reads `dim` columns and answers
  // `num_classes` probabilities per row; an Error naming `where` otherwise.
  static std::shared_ptr<const Booster> fromBlob(std::vector<std::uint8_t> blob, int num_classes,
                                                 int dim, const std::string& where);
  // Class probabilities of `n` rows (row-major, dim values each) into
  // out[0 .. n * num_classes).
  void predict(const float* rows, std::size_t n, float* out) const;
};

namespace xgboost_learner {

// Limits of the stored parameters (the loader and the settings check them).
inline constexpr int kMaxRounds = 10000;
inline constexpr int kMaxDepth = 30;
// Throws an Error naming `where` and the parameter when one is out of range.
void validateParams(const XGBoostParams& p, const std::string& where);
// Throws an Error naming `where` and the call `what` when an XGBoost call returned `rc` != 0.
void check(int rc, const std::string& where, const char* what);
// Tells XGBoost not to log warnings on its own (to stderr); once per process.
void quietXGBoost();
// `v` in full precision, as XGBoost's parameters and our messages take it.
std::string number(double v);

}  // namespace xgboost_learner

}  // namespace findmug
