// findmug/mrf/layout_prior.hpp — a label-layout prior for the MRF's pairwise
// term (mrf.pairwise = layout): which labels meet across a boundary, one
// above the other or side by side, counted on dense label maps (the NYU test
// labels, tools/learn_layout_main.cpp) and stored as a small text file.
//
// The file (models/nyu-layout-prior.csv), `#` lines are comments:
//   findmug-layout-prior,1
//   smoothing,K          add-K (Dirichlet) pseudo-count of every pair
//   offset_px,D          pixel pairs D apart (below / to the right)
//   frames,N             label maps counted
//   vertical,UPPER,LOWER,COUNT      56 rows, every ordered pair of two
//   horizontal,LEFT,RIGHT,COUNT     different label names once per table
// Horizontal counts are symmetric (each pair counted both ways).
//
// From the counts: P(a,b) = (n(a,b) + K) / (N + 56 K) over the pairs a != b,
// the cost of a boundary is -log[P(a,b) / (P_row(a) P_col(b))] (minus the
// pointwise mutual information, so that a label's frequency, which the
// forest already knows, does not count), scaled to [0, 1] per table. An edge
// of the MRF then costs w_ij [a != b] (1 + weight cost(a, b)): Potts times a
// factor that grows for label pairs that rarely meet that way.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "findmug/features/features.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/mrf/mrf.hpp"

namespace findmug {

// Boundary pair counts, [first * kNumLabels + second]; the diagonal stays 0.
using LayoutPairCounts = std::array<double, kNumLabels * kNumLabels>;

struct LayoutCounts {
  LayoutPairCounts vertical{};    // [upper][lower]
  LayoutPairCounts horizontal{};  // [left][right], symmetric
  double smoothing = 1.0;
  int offset_px = 0;
  long frames = 0;
};

// Costs in [0, 1] of each boundary pair, diagonal 0 ([upper][lower] and
// [left][right] as in LayoutCounts).
struct LayoutPrior {
  MrfPairTable vertical{};
  MrfPairTable horizontal{};
};

// Reads the file format above. Errors (findmug::Error) name the file and line.
LayoutCounts parseLayoutCounts(const std::string& text, const std::string& source);
LayoutCounts loadLayoutCounts(const std::string& path);
// The file text; `comment` lines are written first, each prefixed "# ".
std::string formatLayoutCounts(const LayoutCounts& counts, const std::vector<std::string>& comment);

// The smoothed costs. Throws for a negative or non-finite count or smoothing,
// or a table without any count when smoothing is 0.
LayoutPrior layoutPriorFromCounts(const LayoutCounts& counts);
LayoutPrior loadLayoutPrior(const std::string& path);

// The MRF's label-pair factors for one frame: edge (i, j) uses the vertical
// table when the centroid heights (ground frame, m) differ by more than
// `height_threshold` (the higher patch as the upper label), else the
// horizontal one; a non-finite height gives plain Potts. Table entries are
// [a != b] (1 + weight cost(a, b)). Throws for a negative or non-finite
// weight or threshold, or an edge outside `heights`.
void layoutPairFactorsInto(const LayoutPrior& prior, float weight, float height_threshold,
                           const std::vector<float>& heights,
                           const std::vector<std::pair<int, int>>& edges, MrfPairFactors& out);

// The patches' centroid heights above the ground (feature centroid_height)
// for layoutPairFactorsInto.
void patchHeightsInto(const std::vector<FeatureVector>& features, std::vector<float>& heights);

// Minus the mean image row of each of `segments` segments (pixel_segment of
// an image `width` pixels wide, -1 = no segment), so that a higher place in
// the image is a larger value, for mrf.layout_direction = image; NaN for a
// segment without pixels.
void segmentImageHeightsInto(const std::vector<int>& pixel_segment, int width,
                             std::size_t segments, std::vector<float>& heights);

// The "heights" and threshold that mrf.layout_direction asks for.
struct LayoutGeometry {
  const std::vector<int>* pixel_segment = nullptr;
  int width = 0;
  const std::vector<FeatureVector>* features = nullptr;
};
float layoutHeightsInto(const MrfParams& params, const LayoutGeometry& geometry,
                        std::vector<float>& heights);

}  // namespace findmug
