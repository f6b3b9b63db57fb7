// cloud_internal.hpp — what the unit tests need of cloud.cpp beyond the
// public API: the normals with the SIMD path switched off, to check that
// both paths give the same normals bit for bit.
#pragma once

#include "findmug/cloud.hpp"

namespace findmug::detail {

enum class NormalSimd {
  Auto,  // AVX2 where the CPU has it (what computeNormals does)
  Off,   // the scalar code only
};

void computeNormals(const OrganizedCloud& cloud, const NormalConfig& config, NormalImage& out,
                    NormalSimd simd);

}  // namespace findmug::detail
