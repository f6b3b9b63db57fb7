// findmug/offline/layout_counts.hpp — counting the label-layout prior
// (findmug/mrf/layout_prior.hpp) on dense label maps: which labels meet one
// above the other and side by side, and which NYU label maps must be left
// out because they show a scene of the evaluation frames.
#pragma once

#include <cstdint>
#include <set>
#include <vector>

#include "findmug/frame/image_io.hpp"
#include "findmug/mrf/layout_prior.hpp"

namespace findmug {

// Adds the boundary pairs of one label map (findmug label ids, kVoidLabel
// or any id >= kNumLabels is skipped): every pixel p and the pixel `offset`
// rows below it (vertical[label(p)][label(below)]) and `offset` columns to
// its right (horizontal, both orders), where the two labels differ. Adds 1
// to counts.frames. Throws for offset < 1 or a map whose pixel count does not
// match its size.
void addLayoutPairs(const Image<std::uint8_t>& labels, int offset, LayoutCounts& counts);

// The NYU indices among `candidates` that share no scene with any of
// `evaluation` (a scene: a run of consecutive indices on one side of NYU's
// train/test split, nyuSplitRunScenes of cv_folds.hpp), in input order.
std::vector<long> indicesOutsideScenes(const std::vector<long>& candidates,
                                       const std::vector<long>& evaluation,
                                       const std::vector<long>& test_indices);

}  // namespace findmug
