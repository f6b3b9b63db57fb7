#include "findmug/mrf/context_pairwise.hpp"

#include <algorithm>
#include <cmath>

#include "findmug/common/error.hpp"

namespace findmug {

namespace {

// Base feature columns (kFeatureNames).
constexpr int kCentroidHeight = 3, kNormalAngle = 6, kLabL = 8, kLabA = 9, kLabB = 10;

double logistic(double t) { return 1.0 / (1.0 + std::exp(-t)); }

}  // namespace

std::array<float, kPairFeatureDim> pairFeatures(const FeatureVector& a, const FeatureVector& b) {
  const float da = a[kLabA] - b[kLabA], db = a[kLabB] - b[kLabB];
  return {std::abs(a[kLabL] - b[kLabL]), std::sqrt(da * da + db * db),
          std::abs(a[kCentroidHeight] - b[kCentroidHeight]),
          std::abs(a[kNormalAngle] - b[kNormalAngle])};
}

void validatePairwiseContext(const PairwiseContext& m, const std::string& where) {
  auto bad = [&](const std::string& field, double value, const char* expected) {
    throw Error(where + ": learned pairwise term " + field + " = " + std::to_string(value) +
                " (expected " + expected + ")");
  };
  if (!std::isfinite(m.bias)) bad("bias", m.bias, "a finite number");
  for (int k = 0; k < kPairFeatureDim; ++k) {
    const std::string name(kPairFeatureNames[static_cast<std::size_t>(k)]);
    if (!std::isfinite(m.weights[k])) bad("weight of " + name, m.weights[k], "a finite number");
    if (!std::isfinite(m.mean[k])) bad("mean of " + name, m.mean[k], "a finite number");
    if (!(m.scale[k] > 0.0) || !std::isfinite(m.scale[k]))
      bad("scale of " + name, m.scale[k], "a finite number above 0");
  }
  if (!(m.mean_cost > 0.0) || !std::isfinite(m.mean_cost))
    bad("mean cost", m.mean_cost, "a finite number above 0");
  if (m.training_edges == 0) bad("training edge count", 0, "at least 1");
}

double sameLabelProbability(const PairwiseContext& model,
                            const std::array<float, kPairFeatureDim>& x) {
  double t = model.bias;
  for (int k = 0; k < kPairFeatureDim; ++k)
    t += model.weights[k] * (x[k] - model.mean[k]) / model.scale[k];
  return logistic(t);
}

std::vector<float> pairwiseContextScales(const PairwiseContext& model,
                                         const std::vector<FeatureVector>& features,
                                         const std::vector<std::pair<int, int>>& edges) {
  std::vector<float> out;
  pairwiseContextScalesInto(model, features, edges, out);
  return out;
}

void pairwiseContextScalesInto(const PairwiseContext& model,
                               const std::vector<FeatureVector>& features,
                               const std::vector<std::pair<int, int>>& edges,
                               std::vector<float>& out) {
  out.assign(edges.size(), 1.0f);
  const auto n = static_cast<long long>(features.size());
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto [a, b] = edges[k];
    if (a < 0 || b < 0 || a >= n || b >= n)
      throw Error("pairwiseContextScales: edge " + std::to_string(k) + " (" + std::to_string(a) +
                  ", " + std::to_string(b) + ") outside " + std::to_string(n) + " patches");
    const auto x =
        pairFeatures(features[static_cast<std::size_t>(a)], features[static_cast<std::size_t>(b)]);
    bool finite = true;
    for (float v : x) finite = finite && std::isfinite(v);
    // A patch without a finite feature keeps the paper's weight.
    if (finite)
      out[k] = static_cast<float>(contextPartingCost(sameLabelProbability(model, x)) / model.mean_cost);
  }
}

double contextPartingCost(double p_same) { return -std::log1p(-std::min(p_same, 1.0 - 1e-6)); }

}  // namespace findmug
