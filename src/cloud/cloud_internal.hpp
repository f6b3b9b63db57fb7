// cloud_internal.hpp — what the unit tests need of cloud.cpp beyond the
// public API: the cloud, the normals and the ground-frame transforms with the SIMD
// paths switched off, to check that both paths give the same bits.
#pragma once

#include "findmug/cloud/cloud.hpp"

namespace findmug::detail {

enum class CloudSimd {
  Auto,  // AVX2 where the CPU has it (what the public functions do)
  Off,   // the scalar code only
};

void frameToCloud(const RgbdFrame& frame, float max_depth_m, OrganizedCloud& cloud,
                  CloudSimd simd);
void computeNormals(const OrganizedCloud& cloud, const NormalConfig& config, NormalImage& out,
                    CloudSimd simd);
void transformCloud(const OrganizedCloud& cloud, const Eigen::Isometry3f& transform,
                    OrganizedCloud& out, CloudSimd simd);
void rotateNormals(const NormalImage& normals, const Eigen::Matrix3f& rotation, NormalImage& out,
                   CloudSimd simd);

}  // namespace findmug::detail
