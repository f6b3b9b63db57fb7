// Benchmarks of the classification stages: forest prediction for a frame's
// worth of patches (1000 samples, 8 trees of depth 12) and loopy BP on a
// supervoxel-sized graph (~1000 nodes, ~6000 edges). Synthetic inputs of
// realistic size; the data only has to make the trees deep and the graph dense.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "findmug/learner/forest.hpp"
#include "findmug/mrf/mrf.hpp"
#include "mrf/mrf_internal.hpp"

namespace findmug {
namespace {

// Overlapping Gaussian classes, so that trees grow to their full depth.
TrainingSet noisyClasses(int samples, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> mean_dist(0.0f, 4.0f);
  std::normal_distribution<float> noise(0.0f, 1.5f);
  std::array<FeatureVector, kNumLabels> means;
  for (auto& m : means)
    for (float& v : m) v = mean_dist(rng);
  TrainingSet set;
  for (int i = 0; i < samples; ++i) {
    const int c = i % kNumLabels;
    FeatureVector x;
    for (int f = 0; f < kFeatureDim; ++f) x[f] = means[c][f] + noise(rng);
    set.features.push_back(x);
    set.labels.push_back(static_cast<std::uint8_t>(c));
  }
  return set;
}

ForestParams paperParams() {
  ForestParams params;  // defaults: 8 trees, depth 12
  params.num_trees = 8;
  params.max_depth = 12;
  params.num_threads = 2;
  return params;
}

void BM_ForestPredict1000(benchmark::State& state) {
  const RandomForest forest = RandomForest::train(noisyClasses(20000, 1), paperParams());
  const TrainingSet queries = noisyClasses(1000, 2);
  std::size_t nodes = 0;
  for (const auto& tree : forest.trees()) nodes += tree.size();
  for (auto _ : state) {
    for (const auto& x : queries.features) benchmark::DoNotOptimize(forest.predict(x));
  }
  state.counters["samples"] = 1000;
  state.counters["nodes"] = static_cast<double>(nodes);
  state.SetItemsProcessed(state.iterations() * 1000);
}
BENCHMARK(BM_ForestPredict1000)->Unit(benchmark::kMicrosecond);

void BM_ForestTrain20k(benchmark::State& state) {
  const TrainingSet data = noisyClasses(20000, 3);
  for (auto _ : state) benchmark::DoNotOptimize(RandomForest::train(data, paperParams()));
  state.counters["samples"] = 20000;
}
BENCHMARK(BM_ForestTrain20k)->Unit(benchmark::kMillisecond)->Iterations(3);

struct Graph {
  std::vector<ClassProbabilities> unaries;
  std::vector<Eigen::Vector3f> centroids;
  std::vector<std::pair<int, int>> edges;
};

// ~1000 supervoxel centroids in a room-sized box, each joined to its nearest
// neighbours until there are `target_edges` distinct edges (shortest first).
Graph supervoxelGraph(int nodes, std::size_t target_edges) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> x(0.0f, 4.0f), z(0.0f, 2.5f);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  Graph g;
  for (int i = 0; i < nodes; ++i) {
    g.centroids.emplace_back(x(rng), x(rng), z(rng));
    ClassProbabilities p;
    float sum = 0.0f;
    for (float& v : p) sum += (v = std::exp(2.0f * normal(rng)));
    for (float& v : p) v /= sum;
    g.unaries.push_back(p);
  }
  std::set<std::pair<int, int>> seen;
  std::vector<std::pair<float, std::pair<int, int>>> candidates;
  for (int i = 0; i < nodes; ++i) {
    std::vector<std::pair<float, int>> near;
    for (int j = 0; j < nodes; ++j)
      if (j != i) near.emplace_back((g.centroids[i] - g.centroids[j]).norm(), j);
    std::partial_sort(near.begin(), near.begin() + 16, near.end());
    for (int k = 0; k < 16; ++k) {
      const auto edge = std::minmax(i, near[k].second);
      if (seen.insert(edge).second) candidates.push_back({near[k].first, edge});
    }
  }
  std::sort(candidates.begin(), candidates.end());
  for (std::size_t k = 0; k < std::min(target_edges, candidates.size()); ++k)
    g.edges.push_back(candidates[k].second);
  return g;
}

// `simd`: Auto is what the pipeline runs (AVX2 message rounds where the CPU
// has it); Off is Eigen's portable code, for the side-by-side ratio.
void mrf1000Nodes6000Edges(benchmark::State& state, detail::MrfSimd simd) {
  const Graph g = supervoxelGraph(1000, 6000);
  MrfParams params;  // defaults: 30 iterations, damping 0.5
  params.sigma = 0.1f;
  MrfResult result;
  for (auto _ : state) {
    detail::solveMrfInto(g.unaries, g.centroids, g.edges, params, result, simd);
    benchmark::DoNotOptimize(result.labels.data());
  }
  state.counters["nodes"] = static_cast<double>(g.unaries.size());
  state.counters["edges"] = static_cast<double>(g.edges.size());
  state.counters["bp_iterations"] = result.iterations;
  state.counters["converged"] = result.converged ? 1 : 0;
}
void BM_Mrf1000Nodes6000Edges(benchmark::State& state) {
  mrf1000Nodes6000Edges(state, detail::MrfSimd::Auto);
}
void BM_Mrf1000Nodes6000EdgesPortable(benchmark::State& state) {
  mrf1000Nodes6000Edges(state, detail::MrfSimd::Off);
}
BENCHMARK(BM_Mrf1000Nodes6000Edges)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Mrf1000Nodes6000EdgesPortable)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace findmug
