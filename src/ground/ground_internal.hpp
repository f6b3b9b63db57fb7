// ground_internal.hpp — what ground.cpp and ground_gravity.cpp share (a plane, the
// config check, the least-squares refit, a quantile), and what the unit tests need of
// them beyond the public API: the ground estimate with its SIMD paths switched off, to check
// that both paths find the same plane bit for bit.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "findmug/ground/ground.hpp"

namespace findmug::detail {

// Planes whose heights below the camera differ by less than this are one
// level (e.g. a floor split in two by sensor noise).
inline constexpr float kSameLevelM = 0.10f;

// A plane n.p + offset = 0 with n unit and pointing up (camera frame).
struct Plane {
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  float offset = 0.0f;
  float distance(const Eigen::Vector3f& p) const { return normal.dot(p) + offset; }
};
// Throws findmug::Error naming `where` and the ground.* setting out of range.
void validateConfig(const GroundConfig& config, const char* where);
float cosDeg(float deg);
// Least-squares plane (total least squares: centroid + smallest principal axis) through
// points[idx]; keeps the orientation of `hint`.
Plane refitPlane(const std::vector<Eigen::Vector3f>& points, const std::vector<std::size_t>& idx,
                 const Plane& hint);
// Value at fraction q (0..1) of `values` (reorders them).
float quantile(std::vector<float>& values, double q);

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
