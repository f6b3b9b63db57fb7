// findmug/mrf/mrf.hpp — pairwise MRF over the supervoxel adjacency graph.
//
// Energy E(y) = Σ_i λ (1 - p_i(y_i)) + Σ_(i,j) [y_i != y_j] exp(-‖c_i - c_j‖ / σ)
// (the paper's unary and Potts pairwise with centroid distance), minimised
// by min-sum loopy belief propagation with damping.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "findmug/labels/labels.hpp"

namespace findmug {

// The pairwise term (mrf.pairwise): the paper's Potts, or Potts scaled per
// edge by how alike the two patches look, learned from the training frames
// (mrf_context.hpp; findmug-eval only so far: the model file does not carry
// the learned term, and the Segmenter refuses it).
enum class MrfPairwise { Potts, Context };

struct MrfParams {
  MrfPairwise pairwise = MrfPairwise::Potts;
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
// the two patches look (mrf_context.hpp).
MrfResult solveMrfScaled(const std::vector<ClassProbabilities>& unaries,
                         const std::vector<Eigen::Vector3f>& centroids,
                         const std::vector<std::pair<int, int>>& edges,
                         const std::vector<float>& edge_scale, const MrfParams& params);

// The energy above for a labelling, for tests and diagnostics.
double mrfEnergy(const std::vector<ClassProbabilities>& unaries,
                 const std::vector<Eigen::Vector3f>& centroids,
                 const std::vector<std::pair<int, int>>& edges, const MrfParams& params,
                 const std::vector<std::uint8_t>& labels);

}  // namespace findmug
