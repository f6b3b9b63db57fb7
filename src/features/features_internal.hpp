// features_internal.hpp — what the unit tests need of features.cpp beyond
// the public API: the 14-D feature pass with its AVX2 path switched off, to
// check that both paths give the same bits.
#pragma once

#include "findmug/features/features.hpp"

namespace findmug::detail {

enum class FeatureSimd {
  Auto,  // AVX2 where the CPU has it (what computeFeaturesInto does)
  Off,   // the scalar code only
};

void computeFeaturesInto(const OrganizedCloud& cloud_ground, const NormalImage& normals_ground,
                         const Oversegmentation& segmentation, SegmentFeatures& out,
                         FeatureSimd simd);

}  // namespace findmug::detail
