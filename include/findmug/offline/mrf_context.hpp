// findmug/offline/mrf_context.hpp — learning the MRF pairwise term that knows how alike two
// neighbouring patches are (mrf.pairwise = context; the term itself and its use are
// findmug/mrf/context_pairwise.hpp).
//
// A logistic regression of P(same label | colour, height and normal-angle
// differences) over every edge between two labelled patches of the training
// frames. trainModel runs it when the config has mrf.pairwise = context and
// puts the term in the model (RandomForest::setPairwiseContext).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "findmug/features/features.hpp"
#include "findmug/mrf/context_pairwise.hpp"

namespace findmug {

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

}  // namespace findmug
