// Auto-context features: size-weighted means of the first round's class
// distributions over four 3-D neighbourhoods of every patch. All pairs are
// visited (a frame has a few hundred to a few thousand patches, and the
// inner loop is a few compares): simpler and, at these sizes, as fast as a grid.
#include "findmug/features/context_features.hpp"

#include <array>
#include <string>

#include "findmug/common/error.hpp"
#include "common/scratch.hpp"

namespace findmug {

std::vector<std::string> contextFeatureNames() {
  static const char* const kNeighbourhoods[kContextNeighbourhoods] = {"near", "far", "above",
                                                                      "below"};
  std::vector<std::string> names;
  for (const char* h : kNeighbourhoods) {
    for (auto label : kLabelNames)
      names.push_back("ctx_" + std::string(h) + "_" + std::string(label));
  }
  return names;
}

std::vector<float> computeContextFeatures(const std::vector<ClassProbabilities>& probabilities,
                                          const std::vector<Eigen::Vector3f>& centroids,
                                          const std::vector<float>& weights,
                                          const ContextConfig& config) {
  const std::size_t n = probabilities.size();
  if (centroids.size() != n || weights.size() != n) {
    throw Error("computeContextFeatures: " + std::to_string(n) + " distributions, " +
                std::to_string(centroids.size()) + " centroids and " +
                std::to_string(weights.size()) + " weights (must be equal)");
  }
  const float near2 = config.near_m * config.near_m;
  const float far2 = config.far_m * config.far_m;
  const float column2 = config.column_radius_m * config.column_radius_m;
  std::vector<float> out(n * kContextFeatureDim, 0.0f);
  // Weighted distributions, so the inner loop is one multiply-free add.
  // Working memory kept per thread between frames (scratch.hpp).
  thread_local std::vector<ClassProbabilities> weighted_tls;
  detail::Borrowed weighted_buffer(weighted_tls);
  std::vector<ClassProbabilities>& weighted = *weighted_buffer;
  weighted.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    if (!(weights[j] > 0.0f) || !centroids[j].allFinite()) {
      throw Error("computeContextFeatures: patch " + std::to_string(j) +
                  " has a non-positive weight or a non-finite centroid");
    }
    for (int c = 0; c < kNumLabels; ++c) weighted[j][c] = weights[j] * probabilities[j][c];
  }
  for (std::size_t i = 0; i < n; ++i) {
    std::array<ClassProbabilities, kContextNeighbourhoods> sum{};
    std::array<float, kContextNeighbourhoods> total{};
    const Eigen::Vector3f ci = centroids[i];
    auto add = [&](int h, std::size_t j) {
      for (int c = 0; c < kNumLabels; ++c) sum[h][c] += weighted[j][c];
      total[h] += weights[j];
    };
    for (std::size_t j = 0; j < n; ++j) {
      const float dx = centroids[j].x() - ci.x();
      const float dy = centroids[j].y() - ci.y();
      const float dz = centroids[j].z() - ci.z();
      const float horizontal2 = dx * dx + dy * dy;
      const float d2 = horizontal2 + dz * dz;
      if (d2 <= far2) {
        add(1, j);
        if (d2 <= near2) add(0, j);
      }
      if (j != i && horizontal2 <= column2) {
        if (dz > 0.0f)
          add(2, j);
        else if (dz < 0.0f)
          add(3, j);
      }
    }
    float* row = out.data() + i * kContextFeatureDim;
    for (int h = 0; h < kContextNeighbourhoods; ++h) {
      if (total[h] <= 0.0f) continue;
      const float inv = 1.0f / total[h];
      for (int c = 0; c < kNumLabels; ++c) row[h * kNumLabels + c] = sum[h][c] * inv;
    }
  }
  return out;
}

}  // namespace findmug
