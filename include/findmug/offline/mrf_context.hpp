// findmug/offline/mrf_context.hpp — an MRF pairwise term that knows how alike two neighbouring patches are.
//
// The paper's Potts term charges exp(-d/σ) for two neighbours labelled
// differently, whatever they look like; its outlook names colour and height
// differences as simple pairwise features ("especially for similar labels
// such as wall and cabinet"). Here a logistic regression, learned from the
// training frames' labelled neighbours, gives P(same label | colour, height
// and normal-angle differences), and each edge's Potts weight is scaled by
// the cost of parting the two, -log(1 - P), over its mean on the training
// edges (mrf.pairwise = context): neighbours that look alike are held
// together harder, a colour, height or orientation step lets the labels
// part. Solved by solveMrfScaled.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

#include "findmug/features/features.hpp"

namespace findmug {

inline constexpr int kPairFeatureDim = 4;
inline constexpr std::array<std::string_view, kPairFeatureDim> kPairFeatureNames = {
    "lab_l_difference", "lab_ab_difference", "height_difference_m", "normal_angle_difference"};

// Two neighbouring patches' differences, from their 14 base features:
// |ΔL*|, the a*b* distance, |Δ centroid height| (m), |Δ normal angle to the
// vertical| (rad).
std::array<float, kPairFeatureDim> pairFeatures(const FeatureVector& a, const FeatureVector& b);

// The learned term: logit P(same) = bias + Σ w_k (x_k - mean_k) / scale_k.
struct PairwiseContext {
  double bias = 0.0;
  std::array<double, kPairFeatureDim> weights{}, mean{}, scale{1.0, 1.0, 1.0, 1.0};
  double mean_cost = 1.0;  // mean -log(1 - P(same)) over the training edges; scales divide by it
  std::size_t training_edges = 0;
};

// One frame's patches, adjacency and per-patch labels (kNumLabels or more = void).
struct LabelledGraph {
  const std::vector<FeatureVector>* features = nullptr;
  const std::vector<std::pair<int, int>>* edges = nullptr;
  const std::vector<std::uint8_t>* labels = nullptr;
};

// Fits the term on every edge whose two patches are labelled (Newton's
// method on the log-likelihood with a small ridge on the weights). Throws
// findmug::Error when the graphs are inconsistent or no edge is labelled.
PairwiseContext learnPairwiseContext(const std::vector<LabelledGraph>& graphs);

double sameLabelProbability(const PairwiseContext& model,
                            const std::array<float, kPairFeatureDim>& x);

// Per edge: -log(1 - P(same | its differences)) / model.mean_cost, for solveMrfScaled.
std::vector<float> pairwiseContextScales(const PairwiseContext& model,
                                         const std::vector<FeatureVector>& features,
                                         const std::vector<std::pair<int, int>>& edges);

}  // namespace findmug
