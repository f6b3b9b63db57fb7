// findmug/features/context_features.hpp — auto-context: the first forest's answers around a patch.
//
// A table top is a horizontal patch with chairs below its edge and objects
// above it; a chair seat has a chair back above it. The first forest sees
// one patch at a time. The auto-context round (Tu & Bai 2010; the step Wolf
// et al. took next, 2015) gives a second forest the first forest's class
// distributions p(y|x) aggregated over 3-D neighbourhoods of each patch, so
// it can learn such arrangements. Per patch, four size-weighted means of
// p(y|x) over the patches whose centroids (ground frame) lie
//   near   within features.context_near_m of the patch's centroid (itself included)
//   far    within features.context_far_m (itself included)
//   above  higher, within features.context_column_radius_m horizontally
//   below  lower, within features.context_column_radius_m horizontally
// An empty neighbourhood gives all zeros (no class has mass: the forest can
// tell "nothing above" from "wall above"). Column order: neighbourhood-major,
// label-minor, named ctx_<neighbourhood>_<label>.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "findmug/labels/labels.hpp"

namespace findmug {

struct ContextConfig {
  bool enabled = false;          // features.context
  float near_m = 0.3f;           // features.context_near_m
  float far_m = 1.0f;            // features.context_far_m
  float column_radius_m = 0.5f;  // features.context_column_radius_m
  // Training only (not part of the model): the first-round distributions the
  // second round learns from are predicted for each training frame by a
  // first-round forest that did not see it, trained on the other frames in
  // this many groups (cross-fitting). 0 = in-sample predictions of the final
  // first round (overfit: the second round then trusts them too much).
  int cross_fit_folds = 5;  // features.context_cross_fit_folds
};

inline constexpr int kContextNeighbourhoods = 4;
inline constexpr int kContextFeatureDim = kContextNeighbourhoods * kNumLabels;

// The kContextFeatureDim column names, in order.
std::vector<std::string> contextFeatureNames();

// Context columns of every patch, row-major (kContextFeatureDim per patch).
// `weights` are the patches' sizes (e.g. point counts, > 0). Throws
// findmug::Error when the sizes of the inputs disagree.
std::vector<float> computeContextFeatures(const std::vector<ClassProbabilities>& probabilities,
                                          const std::vector<Eigen::Vector3f>& centroids,
                                          const std::vector<float>& weights,
                                          const ContextConfig& config);

}  // namespace findmug
