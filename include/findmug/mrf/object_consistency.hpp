// findmug/mrf/object_consistency.hpp — one opinion per object candidate in the MRF's unaries.
//
// The object candidates of object_features.hpp are nearly pure: labelling each
// with the plurality true label of its patches gives 85.7 % class average on
// the NYU frames (docs/measurements/object-stage.md), while the forest decides
// patch by patch and often splits one table top or cabinet between several
// labels. The MRF's Potts term smooths only between neighbours that touch, and
// less across a crease. This stage gives each patch of an object candidate
//     p'(y) = (1 - w) p(y) + w m(y),
// m the mean of its candidate's distributions weighted by the patches' pixel
// counts, before the table weighting and the MRF (w = mrf.object_consistency).
// Patches of a floor, wall or ceiling plane keep theirs: a wall plane also
// holds the fronts of cabinets and pictures. Cost: one pass over the patches.
#pragma once

#include <array>
#include <vector>

#include "findmug/labels/labels.hpp"

namespace findmug {

// Scratch of mixObjectMeansInPlace (per thread: a stream allocates nothing).
struct ObjectMeanScratch {
  std::vector<std::array<double, kNumLabels>> sums;
};

// `p`: per segment, its distribution; `object_group`: per segment, its object
// candidate (>= 0) or -1 (SegmentFeatures::object_group); `weights`: per
// segment, its pixel count. Throws findmug::Error when the sizes disagree, a
// weight is negative or not finite, or `weight` is outside [0, 1]. An empty
// `object_group` (no object features) or weight 0 leaves `p` as it is.
void mixObjectMeansInPlace(std::vector<ClassProbabilities>& p,
                           const std::vector<int>& object_group,
                           const std::vector<float>& weights, float weight,
                           ObjectMeanScratch& scratch);

}  // namespace findmug
