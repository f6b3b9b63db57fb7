// organized_internal.hpp — internal to findmug_core: what the organized oversegmenter's
// files share (oversegmentation_organized.cpp runs the steps; organized_seeds.cpp places
// the seeds, organized_connectivity.cpp splits and merges the pieces): the feature grid,
// the clusters and the distance weights. Not installed.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"

namespace findmug::detail::organized {

constexpr int kCoarseStride = 2;  // the feature grid keeps one pixel of each 2x2 block
constexpr int kUnassigned = -2;   // usable pixel that no cluster reached

// Per-pixel features, structure of arrays (the assignment loop streams them).
// Invalid pixels have NaN x/y/z, so every distance to them is NaN and never
// wins a comparison.
enum Channel { kL, kA, kB, kX, kY, kZ, kNX, kNY, kNZ, kNumChannels };

struct FeatureGrid {
  int width = 0;
  int height = 0;
  std::array<std::vector<float>, kNumChannels> ch;

  void resize(int w, int h) {
    width = w;
    height = h;
    for (auto& c : ch) c.assign(static_cast<std::size_t>(w) * h, 0.0f);
  }
  bool valid(std::size_t i) const { return !std::isnan(ch[kZ][i]); }
};

struct Cluster {
  std::array<float, kNumChannels> centre{};
  float u = 0, v = 0;          // centre in coarse pixels
  int half_w = 1, half_h = 1;  // search window half size, coarse pixels
  float nominal_area_px = 0;   // full-resolution pixels of its seed cell
};

struct Weights {
  float color;    // color_importance * kLabScale
  float spatial;  // spatial_importance / seed_resolution
  float normal;   // normal_importance
};

// The seeds, into `clusters` (whatever it held before), from the coarse grid and the
// number of usable full pixels of each of its blocks. `avx2`: the seed densities eight
// pixels at a time (the same bits).
void placeSeeds(const OrganizedCloud& cloud, const FeatureGrid& coarse,
                const std::vector<std::uint8_t>& block_valid, const OversegmentationConfig& config,
                const Weights& weights, bool avx2, std::vector<Cluster>& clusters);

// Splits every label into its 4-connected pieces and merges small pieces
// (and usable pixels no cluster reached) into the neighbouring piece they
// share the longest border with. Writes one id per piece group into `out`
// (w x h, sized by the caller).
// `key`: cluster per pixel, kUnassigned, or -1 (unusable: in no piece).
void enforceConnectivity(int w, int h, const std::vector<Cluster>& clusters,
                         const std::vector<int>& key, int min_segment_points,
                         std::vector<int>& out);

}  // namespace findmug::detail::organized
