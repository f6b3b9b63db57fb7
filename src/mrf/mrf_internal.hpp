// mrf_internal.hpp — what the unit tests need of mrf.cpp beyond the public
// API: the solver with its SIMD path switched off, to check that both paths
// give the same messages, labels and confidences bit for bit.
#pragma once

#include "findmug/mrf/mrf.hpp"

namespace findmug::detail {

enum class MrfSimd {
  Auto,  // AVX2 where the CPU has it (what solveMrfInto does)
  Off,   // Eigen's portable code only
};

void solveMrfInto(const std::vector<ClassProbabilities>& unaries,
                  const std::vector<Eigen::Vector3f>& centroids,
                  const std::vector<std::pair<int, int>>& edges, const MrfParams& params,
                  MrfResult& result, MrfSimd simd,
                  const std::vector<float>* edge_scale = nullptr,
                  const MrfPairFactors* factors = nullptr);

}  // namespace findmug::detail
