// ground_internal.hpp — what the unit tests need of ground.cpp beyond the
// public API: the ground estimate with its SIMD paths switched off, to check
// that both paths find the same plane bit for bit.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "findmug/ground/ground.hpp"

namespace findmug::detail {

enum class GroundSimd {
  Auto,  // AVX2 where the CPU has it (what estimateGround does)
  Off,   // portable code only
};

std::optional<GroundPlane> estimateGround(const OrganizedCloud& cloud_camera,
                                          const NormalImage& normals_camera,
                                          const GroundConfig& config, GroundSimd simd);

// The plane-support tests of estimateGround on their own, for points[k] and
// normals[k], k = 0 .. n-1: within `tol` of the plane n.p + offset = 0, with
// a normal within acos(cos_agree) of the plane's. planeSupport lists them as
// the refit selects them; planeSupportCount counts them as RANSAC scores a
// hypothesis.
std::vector<std::size_t> planeSupport(const std::vector<Eigen::Vector3f>& points,
                                      const std::vector<Eigen::Vector3f>& normals,
                                      const Eigen::Vector3f& plane_normal, float plane_offset,
                                      float tol, float cos_agree, GroundSimd simd);
std::size_t planeSupportCount(const std::vector<Eigen::Vector3f>& points,
                              const std::vector<Eigen::Vector3f>& normals,
                              const Eigen::Vector3f& plane_normal, float plane_offset, float tol,
                              float cos_agree, GroundSimd simd);

}  // namespace findmug::detail
