// Internal to findmug_core: the two oversegmenter implementations behind
// makeOversegmenter, and the input check they share. Not installed.
#pragma once

#include <memory>

#include "findmug/oversegmentation/oversegmentation.hpp"

namespace findmug::detail {

std::unique_ptr<Oversegmenter> makePclSupervoxelOversegmenter(const OversegmentationConfig& config);
enum class OversegSimd {
  Auto,  // AVX2 where the CPU has it (what makeOversegmenter builds)
  Off,   // the organized oversegmenter's window search (SSE2), refinement, centre sums and
         // seed density without AVX2
};

std::unique_ptr<Oversegmenter> makeOrganizedOversegmenter(
    const OversegmentationConfig& config, OversegSimd simd = OversegSimd::Auto);

// Throws findmug::Error (prefixed with `who`) unless cloud and normals share
// one non-empty grid and every array has width*height entries.
void checkOversegmentationInput(const OrganizedCloud& cloud, const NormalImage& normals,
                                const char* who);

}  // namespace findmug::detail
