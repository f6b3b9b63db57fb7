#include "findmug/mrf/object_consistency.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "findmug/common/error.hpp"

namespace findmug {

void mixObjectMeansInPlace(std::vector<ClassProbabilities>& p,
                           const std::vector<int>& object_group,
                           const std::vector<float>& weights, float weight,
                           ObjectMeanScratch& scratch) {
  if (!(weight >= 0.0f && weight <= 1.0f))
    throw Error("mixObjectMeansInPlace: weight " + std::to_string(weight) + " outside [0, 1]");
  if (object_group.empty() || weight == 0.0f) return;
  const std::size_t n = p.size();
  if (object_group.size() != n || weights.size() != n) {
    throw Error("mixObjectMeansInPlace: " + std::to_string(n) + " distributions, " +
                std::to_string(object_group.size()) + " object groups and " +
                std::to_string(weights.size()) + " weights");
  }
  int groups = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (!(weights[k] >= 0.0f) || !std::isfinite(weights[k]))
      throw Error("mixObjectMeansInPlace: segment " + std::to_string(k) + " has weight " +
                  std::to_string(weights[k]));
    groups = std::max(groups, object_group[k] + 1);
  }
  auto& sums = scratch.sums;
  sums.assign(static_cast<std::size_t>(groups), std::array<double, kNumLabels>{});
  for (std::size_t k = 0; k < n; ++k) {
    const int g = object_group[k];
    if (g < 0) continue;
    auto& sum = sums[static_cast<std::size_t>(g)];
    for (int c = 0; c < kNumLabels; ++c) sum[c] += static_cast<double>(weights[k]) * p[k][c];
  }
  // Each sum becomes its candidate's mean distribution; a candidate whose
  // patches all weigh 0 has none and its patches keep their own.
  for (auto& sum : sums) {
    double total = 0;
    for (const double v : sum) total += v;
    if (total > 0)
      for (double& v : sum) v /= total;
  }
  for (std::size_t k = 0; k < n; ++k) {
    const int g = object_group[k];
    if (g < 0) continue;
    const auto& mean = sums[static_cast<std::size_t>(g)];
    double total = 0;
    for (const double v : mean) total += v;
    if (!(total > 0)) continue;  // every patch of the candidate has weight 0
    for (int c = 0; c < kNumLabels; ++c)
      p[k][c] = static_cast<float>((1.0 - weight) * p[k][c] + weight * mean[c]);
  }
}

}  // namespace findmug
