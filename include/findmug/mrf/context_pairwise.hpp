// findmug/mrf/context_pairwise.hpp — the learned pairwise term of mrf.pairwise = context.
//
// The paper's Potts term charges exp(-d/σ) for two neighbours labelled
// differently, whatever they look like; its outlook names colour and height
// differences as simple pairwise features ("especially for similar labels
// such as wall and cabinet"). Here a logistic regression, learned from the
// training frames' labelled neighbours (learnPairwiseContext in
// findmug/offline/mrf_context.hpp, run by findmug-train), gives P(same label |
// colour, height and normal-angle differences), and each edge's Potts weight
// is scaled by the cost of parting the two, -log(1 - P), over its mean on the
// training edges: neighbours that look alike are held together harder, a
// colour, height or orientation step lets the labels part (solveMrfScaledInto).
// The term is part of the model file (format 5), because it is learned from
// the same frames as the forest; the Segmenter refuses mrf.pairwise = context
// with a model that does not carry one.
#pragma once

#include <array>
#include <cstddef>
#include <string>
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
  bool operator==(const PairwiseContext&) const = default;
};

// Throws findmug::Error naming `where` and the field when a term cannot be
// used: a value that is not finite, a scale or mean cost that is not
// positive, no training edge.
void validatePairwiseContext(const PairwiseContext& model, const std::string& where);

double sameLabelProbability(const PairwiseContext& model,
                            const std::array<float, kPairFeatureDim>& x);
// The cost of parting two neighbours, -log(1 - P(same)), with P capped below
// 1 so that it stays finite: the negative log-likelihood of "they differ".
double contextPartingCost(double p_same);

// Per edge: -log(1 - P(same | its differences)) / model.mean_cost, the
// factor on its Potts weight (1 where a patch has a feature that is not
// finite). Throws findmug::Error for an edge outside `features`.
std::vector<float> pairwiseContextScales(const PairwiseContext& model,
                                         const std::vector<FeatureVector>& features,
                                         const std::vector<std::pair<int, int>>& edges);
// The same into `out`, reusing its memory.
void pairwiseContextScalesInto(const PairwiseContext& model,
                               const std::vector<FeatureVector>& features,
                               const std::vector<std::pair<int, int>>& edges,
                               std::vector<float>& out);

}  // namespace findmug
