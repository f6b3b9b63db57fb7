// findmug/mrf/mrf.hpp — pairwise MRF over the patch adjacency graph.
//
// Energy E(y) = Σ_i λ (1 - p_i(y_i)) + Σ_(i,j) [y_i != y_j] exp(-‖c_i - c_j‖ / σ)
// (the paper's unary and Potts pairwise with centroid distance), minimised
// by min-sum loopy belief propagation with damping.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "findmug/labels/labels.hpp"

namespace findmug {

// The pairwise term (mrf.pairwise): the paper's Potts, or Potts scaled per
// edge by how alike the two patches look, learned from the training frames
// and carried by the model (context_pairwise.hpp), or Potts times a
// label-pair factor from a label-layout prior file (layout_prior.hpp).
enum class MrfPairwise { Potts, Context, Layout };
// mrf.layout_direction: which neighbour of an edge is the upper one for the
// layout prior: by ground-frame centroid height, or by mean image row (the
// prior's own sense of "above", counted in label images).
enum class LayoutDirection { Height, Image };

struct MrfParams {
  MrfPairwise pairwise = MrfPairwise::Potts;
  // mrf.pairwise = layout: the prior file, how strongly an unlikely label
  // pair is penalised, and the centroid height difference (m) above which
  // two neighbours count as one above the other.
  std::string layout_prior_path = "models/nyu-layout-prior.csv";
  float layout_weight = 1.0f;
  float layout_height_threshold = 0.1f;
  LayoutDirection layout_direction = LayoutDirection::Height;
  float layout_image_threshold_px = 10.0f;  // the same for layout_direction = image
  // mrf.object_consistency: the share w of each object candidate's mean
  // distribution mixed into its patches' unaries (object_consistency.hpp);
  // 0 = off (the paper's unaries). Without features.objects there are no
  // candidates and it changes nothing (a model without object features, as
  // the demo's, runs with the shipped file as it is).
  float object_consistency = 0.0f;
  float lambda = 1.0f;        // unary weight
  float sigma = 0.1f;         // metres; pairwise decay with centroid distance
  int max_iterations = 30;
  float damping = 0.5f;       // new message = (1-d)*computed + d*old
  float convergence_tol = 1e-4f;
};

struct MrfResult {
  std::vector<std::uint8_t> labels;  // one per node
  std::vector<float> confidence;     // normalised belief of the chosen label:
                                     // exp(-b(y)) / Σ_y' exp(-b(y')), in [1/8, 1]
  int iterations = 0;
  bool converged = false;
};

// Throws findmug::Error on sizes that differ, edges out of range or
// self-edges, non-finite/non-probability unaries and invalid parameters.
// Nodes without edges get the argmax of their p.
MrfResult solveMrf(const std::vector<ClassProbabilities>& unaries,
                   const std::vector<Eigen::Vector3f>& centroids,
                   const std::vector<std::pair<int, int>>& edges, const MrfParams& params);
// The same into `out`, reusing the memory it holds.
void solveMrfInto(const std::vector<ClassProbabilities>& unaries,
                  const std::vector<Eigen::Vector3f>& centroids,
                  const std::vector<std::pair<int, int>>& edges, const MrfParams& params,
                  MrfResult& out);

// The same with each edge k's Potts weight multiplied by edge_scale[k]
// (finite, >= 0; one per edge): a pairwise term that also knows how alike
// the two patches look (context_pairwise.hpp).
MrfResult solveMrfScaled(const std::vector<ClassProbabilities>& unaries,
                         const std::vector<Eigen::Vector3f>& centroids,
                         const std::vector<std::pair<int, int>>& edges,
                         const std::vector<float>& edge_scale, const MrfParams& params);
// The same into `out`, reusing the memory it holds.
void solveMrfScaledInto(const std::vector<ClassProbabilities>& unaries,
                        const std::vector<Eigen::Vector3f>& centroids,
                        const std::vector<std::pair<int, int>>& edges,
                        const std::vector<float>& edge_scale, const MrfParams& params,
                        MrfResult& out);

// Label-pair factors: the pairwise cost of edge k is its Potts weight times
// tables[table_of_edge[k]][y_first * kNumLabels + y_second] (y_first the
// label of edges[k].first) instead of times [y_first != y_second]. Entries
// finite and >= 0; the tables need not be symmetric (layout_prior.hpp).
using MrfPairTable = std::array<float, kNumLabels * kNumLabels>;
struct MrfPairFactors {
  std::vector<MrfPairTable> tables;
  std::vector<std::uint8_t> table_of_edge;  // one per edge
};
// The Potts indicator as a table: 0 on the diagonal, 1 elsewhere.
MrfPairTable pottsPairTable();

// solveMrfInto with label-pair factors. Messages cost O(L^2) per edge
// instead of O(L).
void solveMrfWithFactorsInto(const std::vector<ClassProbabilities>& unaries,
                             const std::vector<Eigen::Vector3f>& centroids,
                             const std::vector<std::pair<int, int>>& edges,
                             const MrfPairFactors& factors, const MrfParams& params,
                             MrfResult& out);

// The energy above for a labelling, for tests and diagnostics.
double mrfEnergy(const std::vector<ClassProbabilities>& unaries,
                 const std::vector<Eigen::Vector3f>& centroids,
                 const std::vector<std::pair<int, int>>& edges, const MrfParams& params,
                 const std::vector<std::uint8_t>& labels);

}  // namespace findmug
