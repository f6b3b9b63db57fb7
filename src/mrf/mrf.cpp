// Pairwise MRF over the patch adjacency graph, solved by min-sum loopy
// belief propagation.
//
// Unary cost U_i(y) = λ (1 - p_i(y)); Potts pairwise cost w_ij [y_i != y_j]
// with w_ij = exp(-‖c_i - c_j‖ / σ). Messages live on directed edges: edge k
// of the input gives directed edges 2k (a -> b) and 2k+1 (b -> a), so the
// reverse of directed edge e is e ^ 1.
//
// Potts makes a message cheap: with h(y) = belief of the sender minus the
// message it got from the receiver,
//   m(y) = min( h(y), min_y' h(y') + w ) - min_y' h(y')
//        = min( h(y) - min h, w ),
// which is O(L) instead of O(L^2). Messages are normalised (minimum 0), so
// they stay within [0, w] ⊂ [0, 1] and an absolute convergence tolerance is
// meaningful. Updates are synchronous (all messages from the previous
// iteration's beliefs) with damping, which makes the result independent of
// the edge order and helps convergence on loopy graphs.
//
// With label-pair factors (solveMrfWithFactorsInto) the pairwise cost is
// w_ij T(y_i, y_j) for a table T per edge, and a message is the full
// m(y) = min_y' [ h(y') - min h + w T(y', y) ], O(L^2); the Potts table gives
// back the message above.
#include "findmug/mrf/mrf.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "common/cpu_features.hpp"
#include "common/scratch.hpp"
#include "findmug/common/error.hpp"
#include "mrf/mrf_internal.hpp"

namespace findmug {

namespace {

// Fixed-size Eigen arrays so that the per-label loops (add, min, clamp)
// compile to SIMD instructions without relying on -ffast-math.
using Costs = Eigen::Array<float, kNumLabels, 1>;

void validateParams(const MrfParams& p) {
  auto fail = [](const std::string& field, float value, const std::string& rule) {
    throw Error("MRF parameter " + field + " = " + std::to_string(value) + " is invalid (" + rule +
                ")");
  };
  if (!(std::isfinite(p.lambda) && p.lambda >= 0.0f)) fail("lambda", p.lambda, "expected >= 0");
  if (!(std::isfinite(p.sigma) && p.sigma > 0.0f)) fail("sigma", p.sigma, "expected > 0");
  if (p.max_iterations < 0)
    fail("max_iterations", static_cast<float>(p.max_iterations), "expected >= 0");
  if (!(p.damping >= 0.0f && p.damping < 1.0f)) fail("damping", p.damping, "expected in [0, 1)");
  if (!(std::isfinite(p.convergence_tol) && p.convergence_tol >= 0.0f))
    fail("convergence_tol", p.convergence_tol, "expected >= 0");
}

void validateGraph(const std::vector<ClassProbabilities>& unaries,
                   const std::vector<Eigen::Vector3f>& centroids,
                   const std::vector<std::pair<int, int>>& edges) {
  if (unaries.size() != centroids.size())
    throw Error("MRF: " + std::to_string(unaries.size()) + " unaries but " +
                std::to_string(centroids.size()) + " centroids");
  // Probabilities from the forest; a little slack for rounding.
  constexpr float kSlack = 1e-3f;
  for (std::size_t i = 0; i < unaries.size(); ++i) {
    for (int y = 0; y < kNumLabels; ++y) {
      const float p = unaries[i][y];
      if (!(std::isfinite(p) && p >= -kSlack && p <= 1.0f + kSlack))
        throw Error("MRF: unary of node " + std::to_string(i) + " label " +
                    std::string(kLabelNames[y]) + " is " + std::to_string(p) +
                    " (expected a probability)");
    }
    if (!centroids[i].allFinite())
      throw Error("MRF: centroid of node " + std::to_string(i) + " is not finite");
  }
  const auto n = static_cast<long long>(unaries.size());
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto [a, b] = edges[k];
    if (a < 0 || b < 0 || a >= n || b >= n)
      throw Error("MRF: edge " + std::to_string(k) + " (" + std::to_string(a) + ", " +
                  std::to_string(b) + ") refers to a node outside 0.." + std::to_string(n - 1));
    if (a == b)
      throw Error("MRF: edge " + std::to_string(k) + " is a self-edge on node " +
                  std::to_string(a));
  }
}

float pairwiseWeight(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float sigma) {
  return std::exp(-(a - b).norm() / sigma);
}

void validateFactors(const MrfPairFactors& factors, std::size_t num_edges) {
  if (factors.table_of_edge.size() != num_edges)
    throw Error("MRF: " + std::to_string(factors.table_of_edge.size()) +
                " pair-table indices for " + std::to_string(num_edges) + " edges");
  for (std::size_t k = 0; k < num_edges; ++k)
    if (factors.table_of_edge[k] >= factors.tables.size())
      throw Error("MRF: edge " + std::to_string(k) + " refers to pair table " +
                  std::to_string(factors.table_of_edge[k]) + " of " +
                  std::to_string(factors.tables.size()));
  for (std::size_t t = 0; t < factors.tables.size(); ++t)
    for (float v : factors.tables[t])
      if (!(std::isfinite(v) && v >= 0.0f))
        throw Error("MRF: pair table " + std::to_string(t) + " holds " + std::to_string(v) +
                    " (expected a finite number >= 0)");
}

// One message of a directed edge through a label-pair table: `table` is
// indexed [sender label * L + receiver label].
Costs factorMessage(const Costs& h, const float* table, float w) {
  const Costs shifted = h - h.minCoeff();
  Costs m = shifted[0] + w * Eigen::Map<const Costs>(table);
  for (int y = 1; y < kNumLabels; ++y)
    m = m.min(shifted[y] + w * Eigen::Map<const Costs>(table + y * kNumLabels));
  return m;
}

#if defined(FINDMUG_AVX2_DISPATCH)
static_assert(kNumLabels == 8 && sizeof(Costs) == 8 * sizeof(float),
              "the AVX2 path holds one node's costs in one register");

// The minimum (or maximum) of v's eight lanes, in every lane. Exact in any
// order, so it matches the portable code's minCoeff/maxCoeff.
__attribute__((target("avx2"))) inline __m256 pickExtreme(__m256 a, __m256 b, bool maximum) {
  return maximum ? _mm256_max_ps(a, b) : _mm256_min_ps(a, b);
}
__attribute__((target("avx2"))) inline __m256 laneExtreme(__m256 v, bool maximum) {
  __m256 t = pickExtreme(v, _mm256_permute2f128_ps(v, v, 1), maximum);
  t = pickExtreme(t, _mm256_shuffle_ps(t, t, _MM_SHUFFLE(1, 0, 3, 2)), maximum);
  return pickExtreme(t, _mm256_shuffle_ps(t, t, _MM_SHUFFLE(2, 3, 0, 1)), maximum);
}
__attribute__((target("avx2"))) inline __m256 laneMin(__m256 v) { return laneExtreme(v, false); }
__attribute__((target("avx2"))) inline __m256 laneMax(__m256 v) { return laneExtreme(v, true); }

// computeBeliefs of solveMrfInto: each node's unary plus its incoming
// messages, added in the same order.
__attribute__((target("avx2"))) void beliefsAvx2(const Costs* unary, const Costs* messages,
                                                 const std::uint32_t* in_begin,
                                                 const std::uint32_t* incoming,
                                                 std::size_t num_nodes, Costs* belief) {
  for (std::size_t i = 0; i < num_nodes; ++i) {
    __m256 b = _mm256_loadu_ps(unary[i].data());
    for (std::uint32_t k = in_begin[i]; k < in_begin[i + 1]; ++k)
      b = _mm256_add_ps(b, _mm256_loadu_ps(messages[incoming[k]].data()));
    _mm256_storeu_ps(belief[i].data(), b);
  }
}

// One round of messages of solveMrfInto's loop, one directed edge's eight
// labels per register (Eigen's portable code takes two SSE halves). The
// same operations per label in the same order (no FMA: the target is
// "avx2", not "fma"), and min/max are exact in any order, so the same
// messages to the bit. Returns the largest change of any message entry.
__attribute__((target("avx2"))) float messageRoundAvx2(const Costs* belief, const Costs* messages,
                                                       const std::uint32_t* source,
                                                       const float* weight,
                                                       std::size_t num_directed, float take,
                                                       float keep, Costs* next) {
  const __m256 take8 = _mm256_set1_ps(take);
  const __m256 keep8 = _mm256_set1_ps(keep);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  __m256 max_change = _mm256_setzero_ps();
  for (std::size_t e = 0; e < num_directed; ++e) {
    const __m256 h = _mm256_sub_ps(_mm256_loadu_ps(belief[source[e]].data()),
                                   _mm256_loadu_ps(messages[e ^ 1].data()));
    const __m256 old = _mm256_loadu_ps(messages[e].data());
    __m256 m = _mm256_add_ps(_mm256_mul_ps(take8, _mm256_min_ps(_mm256_sub_ps(h, laneMin(h)),
                                                                _mm256_set1_ps(weight[e / 2]))),
                             _mm256_mul_ps(keep8, old));
    m = _mm256_sub_ps(m, laneMin(m));
    max_change = _mm256_max_ps(max_change, _mm256_and_ps(_mm256_sub_ps(m, old), abs_mask));
    _mm256_storeu_ps(next[e].data(), m);
  }
  return _mm_cvtss_f32(_mm256_castps256_ps128(laneMax(max_change)));
}
#endif

}  // namespace

MrfResult solveMrf(const std::vector<ClassProbabilities>& unaries,
                   const std::vector<Eigen::Vector3f>& centroids,
                   const std::vector<std::pair<int, int>>& edges, const MrfParams& params) {
  MrfResult result;
  solveMrfInto(unaries, centroids, edges, params, result);
  return result;
}

void solveMrfInto(const std::vector<ClassProbabilities>& unaries,
                  const std::vector<Eigen::Vector3f>& centroids,
                  const std::vector<std::pair<int, int>>& edges, const MrfParams& params,
                  MrfResult& result) {
  detail::solveMrfInto(unaries, centroids, edges, params, result, detail::MrfSimd::Auto);
}

MrfPairTable pottsPairTable() {
  MrfPairTable t{};
  for (int a = 0; a < kNumLabels; ++a)
    for (int b = 0; b < kNumLabels; ++b) t[a * kNumLabels + b] = a == b ? 0.0f : 1.0f;
  return t;
}

void solveMrfWithFactorsInto(const std::vector<ClassProbabilities>& unaries,
                             const std::vector<Eigen::Vector3f>& centroids,
                             const std::vector<std::pair<int, int>>& edges,
                             const MrfPairFactors& factors, const MrfParams& params,
                             MrfResult& out) {
  detail::solveMrfInto(unaries, centroids, edges, params, out, detail::MrfSimd::Auto, nullptr,
                       &factors);
}

MrfResult solveMrfScaled(const std::vector<ClassProbabilities>& unaries,
                         const std::vector<Eigen::Vector3f>& centroids,
                         const std::vector<std::pair<int, int>>& edges,
                         const std::vector<float>& edge_scale, const MrfParams& params) {
  MrfResult result;
  solveMrfScaledInto(unaries, centroids, edges, edge_scale, params, result);
  return result;
}

void solveMrfScaledInto(const std::vector<ClassProbabilities>& unaries,
                        const std::vector<Eigen::Vector3f>& centroids,
                        const std::vector<std::pair<int, int>>& edges,
                        const std::vector<float>& edge_scale, const MrfParams& params,
                        MrfResult& out) {
  detail::solveMrfInto(unaries, centroids, edges, params, out, detail::MrfSimd::Auto, &edge_scale);
}

namespace {

void validateEdgeScale(const std::vector<float>& edge_scale, std::size_t num_edges) {
  if (edge_scale.size() != num_edges)
    throw Error("MRF: " + std::to_string(edge_scale.size()) + " edge scales for " +
                std::to_string(num_edges) + " edges");
  for (std::size_t k = 0; k < edge_scale.size(); ++k)
    if (!(std::isfinite(edge_scale[k]) && edge_scale[k] >= 0.0f))
      throw Error("MRF: scale of edge " + std::to_string(k) + " is " +
                  std::to_string(edge_scale[k]) + " (expected a finite number >= 0)");
}

// The graph as message passing walks it: directed edge 2k runs from edges[k].first to
// edges[k].second, 2k+1 back; each undirected edge's Potts weight (times its scale);
// every node's incoming directed edges (CSR: incoming[in_begin[i] .. in_begin[i+1])).
struct DirectedGraph {
  std::vector<std::uint32_t>& source;
  std::vector<std::uint32_t>& target;
  std::vector<float>& weight;
  std::vector<std::uint32_t>& in_begin;
  std::vector<std::uint32_t>& incoming;
};

void buildDirectedGraph(const std::vector<Eigen::Vector3f>& centroids,
                        const std::vector<std::pair<int, int>>& edges, float sigma,
                        const std::vector<float>* edge_scale, std::size_t num_nodes,
                        std::vector<std::uint32_t>& fill, DirectedGraph& g) {
  const std::size_t num_directed = 2 * edges.size();
  g.source.resize(num_directed);
  g.target.resize(num_directed);
  g.weight.resize(edges.size());
  g.in_begin.assign(num_nodes + 1, 0);
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto a = static_cast<std::uint32_t>(edges[k].first);
    const auto b = static_cast<std::uint32_t>(edges[k].second);
    g.source[2 * k] = a;
    g.target[2 * k] = b;
    g.source[2 * k + 1] = b;
    g.target[2 * k + 1] = a;
    g.weight[k] = pairwiseWeight(centroids[a], centroids[b], sigma);
    if (edge_scale) g.weight[k] *= (*edge_scale)[k];
    ++g.in_begin[a + 1];
    ++g.in_begin[b + 1];
  }
  for (std::size_t i = 0; i < num_nodes; ++i) g.in_begin[i + 1] += g.in_begin[i];
  g.incoming.resize(num_directed);
  fill.assign(g.in_begin.begin(), g.in_begin.end() - 1);
  for (std::size_t e = 0; e < num_directed; ++e)
    g.incoming[fill[g.target[e]]++] = static_cast<std::uint32_t>(e);
}

// Each table as the message of a directed edge reads it: [sender][receiver].
// Directed edge 2k sends from edges[k].first (the table as given), 2k+1
// from edges[k].second (its transpose).
void orientTables(const MrfPairFactors& factors, std::vector<MrfPairTable>& oriented) {
  oriented.clear();
  for (const MrfPairTable& t : factors.tables) {
    oriented.push_back(t);
    MrfPairTable transposed{};
    for (int a = 0; a < kNumLabels; ++a)
      for (int b = 0; b < kNumLabels; ++b) transposed[b * kNumLabels + a] = t[a * kNumLabels + b];
    oriented.push_back(transposed);
  }
}

// belief[i] = unary[i] + the messages into i.
void computeBeliefs(bool avx2, const std::vector<Costs>& unary, const std::vector<Costs>& messages,
                    const DirectedGraph& g, std::vector<Costs>& belief) {
#if defined(FINDMUG_AVX2_DISPATCH)
  if (avx2) {
    beliefsAvx2(unary.data(), messages.data(), g.in_begin.data(), g.incoming.data(), unary.size(),
                belief.data());
    return;
  }
#else
  (void)avx2;
#endif
  for (std::size_t i = 0; i < unary.size(); ++i) {
    Costs b = unary[i];
    for (std::uint32_t k = g.in_begin[i]; k < g.in_begin[i + 1]; ++k) b += messages[g.incoming[k]];
    belief[i] = b;
  }
}

// One damped round of min-sum messages into `next`: the learned tables' messages with
// factors, else Potts (AVX2 or portable, the same bits). Returns the largest change.
float messageRound(bool avx2, const std::vector<Costs>& belief, const std::vector<Costs>& messages,
                   const DirectedGraph& g, const MrfPairFactors* factors,
                   const std::vector<MrfPairTable>& oriented, float take, float keep,
                   std::vector<Costs>& next) {
  const std::size_t num_directed = messages.size();
  float max_change = 0.0f;
  if (factors) {
    for (std::size_t e = 0; e < num_directed; ++e) {
      const Costs h = belief[g.source[e]] - messages[e ^ 1];
      const Costs& old = messages[e];
      const float* table = oriented[2 * factors->table_of_edge[e / 2] + (e & 1)].data();
      Costs m = take * factorMessage(h, table, g.weight[e / 2]) + keep * old;
      m -= m.minCoeff();
      max_change = std::max(max_change, (m - old).abs().maxCoeff());
      next[e] = m;
    }
    return max_change;
  }
#if defined(FINDMUG_AVX2_DISPATCH)
  if (avx2) {
    return messageRoundAvx2(belief.data(), messages.data(), g.source.data(), g.weight.data(),
                            num_directed, take, keep, next.data());
  }
#else
  (void)avx2;
#endif
  for (std::size_t e = 0; e < num_directed; ++e) {
    const Costs h = belief[g.source[e]] - messages[e ^ 1];
    const Costs& old = messages[e];
    Costs m = take * (h - h.minCoeff()).min(g.weight[e / 2]) + keep * old;
    m -= m.minCoeff();
    max_change = std::max(max_change, (m - old).abs().maxCoeff());
    next[e] = m;
  }
  return max_change;
}

// Labels and confidences from the final beliefs.
void decideLabels(const std::vector<Costs>& belief, const std::vector<ClassProbabilities>& unaries,
                  MrfResult& result) {
  const std::size_t num_nodes = belief.size();
  result.labels.resize(num_nodes);
  result.confidence.resize(num_nodes);
  for (std::size_t i = 0; i < num_nodes; ++i) {
    const Costs& b = belief[i];
    // Lowest belief wins; ties (e.g. λ = 0, or an isolated node with equal
    // probabilities) go to the higher forest probability, then the lower id.
    // For an isolated node this is exactly the argmax of p.
    int best = 0;
    for (int y = 1; y < kNumLabels; ++y) {
      if (b[y] < b[best] || (b[y] == b[best] && unaries[i][y] > unaries[i][best])) best = y;
    }
    // Confidence: exp(-b) normalised over the labels, i.e. a softmax of the
    // negated beliefs, evaluated relative to the minimum for stability.
    double z = 0.0;
    for (int y = 0; y < kNumLabels; ++y) z += std::exp(-static_cast<double>(b[y] - b[best]));
    result.labels[i] = static_cast<std::uint8_t>(best);
    result.confidence[i] = static_cast<float>(1.0 / z);
  }
}

}  // namespace

void detail::solveMrfInto(const std::vector<ClassProbabilities>& unaries,
                          const std::vector<Eigen::Vector3f>& centroids,
                          const std::vector<std::pair<int, int>>& edges, const MrfParams& params,
                          MrfResult& result, MrfSimd simd, const std::vector<float>* edge_scale,
                          const MrfPairFactors* factors) {
  validateParams(params);
  validateGraph(unaries, centroids, edges);
  if (factors) validateFactors(*factors, edges.size());
  if (edge_scale) validateEdgeScale(*edge_scale, edges.size());

  const std::size_t num_nodes = unaries.size();
  const std::size_t num_directed = 2 * edges.size();

  // Working memory kept per thread between frames (scratch.hpp).
  struct Buffers {
    std::vector<Costs> unary, messages, next, belief;
    std::vector<std::uint32_t> source, target, in_begin, incoming, fill;
    std::vector<float> weight;
    std::vector<MrfPairTable> oriented;
  };
  thread_local Buffers buffers;
  detail::Borrowed unary_buffer(buffers.unary), messages_buffer(buffers.messages),
      next_buffer(buffers.next), belief_buffer(buffers.belief);
  detail::Borrowed source_buffer(buffers.source), target_buffer(buffers.target),
      in_begin_buffer(buffers.in_begin), incoming_buffer(buffers.incoming),
      fill_buffer(buffers.fill);
  detail::Borrowed weight_buffer(buffers.weight);
  detail::Borrowed oriented_buffer(buffers.oriented);

  // Unary costs λ(1 − p).
  std::vector<Costs>& unary = *unary_buffer;
  unary.resize(num_nodes);
  for (std::size_t i = 0; i < num_nodes; ++i)
    unary[i] = params.lambda * (1.0f - Eigen::Map<const Costs>(unaries[i].data()));

  DirectedGraph graph{*source_buffer, *target_buffer, *weight_buffer, *in_begin_buffer,
                      *incoming_buffer};
  buildDirectedGraph(centroids, edges, params.sigma, edge_scale, num_nodes, *fill_buffer, graph);
  std::vector<MrfPairTable>& oriented = *oriented_buffer;
  oriented.clear();
  if (factors) orientTables(*factors, oriented);

  std::vector<Costs>& messages = *messages_buffer;
  messages.assign(num_directed, Costs::Zero());
  std::vector<Costs>& next = *next_buffer;
  next.resize(num_directed);
  std::vector<Costs>& belief = *belief_buffer;
  belief.resize(num_nodes);
#if defined(FINDMUG_AVX2_DISPATCH)
  const bool avx2 = simd == detail::MrfSimd::Auto && detail::cpuHasAvx2();
#else
  (void)simd;  // no SIMD path on this platform
  const bool avx2 = false;
#endif

  result.iterations = 0;
  result.converged = edges.empty();
  const float keep = params.damping;
  const float take = 1.0f - params.damping;
  for (int iter = 0; iter < params.max_iterations && !edges.empty(); ++iter) {
    computeBeliefs(avx2, unary, messages, graph, belief);
    const float max_change =
        messageRound(avx2, belief, messages, graph, factors, oriented, take, keep, next);
    messages.swap(next);
    result.iterations = iter + 1;
    if (max_change < params.convergence_tol) {
      result.converged = true;
      break;
    }
  }
  computeBeliefs(avx2, unary, messages, graph, belief);
  decideLabels(belief, unaries, result);
}

double mrfEnergy(const std::vector<ClassProbabilities>& unaries,
                 const std::vector<Eigen::Vector3f>& centroids,
                 const std::vector<std::pair<int, int>>& edges, const MrfParams& params,
                 const std::vector<std::uint8_t>& labels) {
  validateParams(params);
  validateGraph(unaries, centroids, edges);
  if (labels.size() != unaries.size())
    throw Error("mrfEnergy: " + std::to_string(labels.size()) + " labels for " +
                std::to_string(unaries.size()) + " nodes");
  double energy = 0.0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (labels[i] >= kNumLabels)
      throw Error("mrfEnergy: node " + std::to_string(i) + " has label " +
                  std::to_string(labels[i]) + " (expected 0.." + std::to_string(kNumLabels - 1) +
                  ")");
    energy +=
        static_cast<double>(params.lambda) * (1.0 - static_cast<double>(unaries[i][labels[i]]));
  }
  for (const auto& [a, b] : edges) {
    if (labels[static_cast<std::size_t>(a)] != labels[static_cast<std::size_t>(b)])
      energy += pairwiseWeight(centroids[static_cast<std::size_t>(a)],
                               centroids[static_cast<std::size_t>(b)], params.sigma);
  }
  return energy;
}

}  // namespace findmug
