// semantic_map_internal.hpp — what the semantic map's source files share (internal to
// src/map): voxel keys (three 21-bit signed indices in one 64-bit key), the bound on poses,
// number formatting for messages, and the hull test the tables' support uses.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"

namespace findmug::semantic_map_detail {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr int kKeyBits = 21;
inline constexpr std::int64_t kKeyOffset = std::int64_t{1} << (kKeyBits - 1);
inline constexpr std::uint64_t kKeyMask = (std::uint64_t{1} << kKeyBits) - 1;
inline constexpr double kMaxPoseDistanceM = 10000.0;

inline std::string fmt(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

[[noreturn]] inline void badSetting(const std::string& key, double value, const std::string& rule) {
  throw Error("semantic_map." + key + " = " + fmt(value) + ": " + rule);
}

inline std::uint64_t packIndices(std::int64_t x, std::int64_t y, std::int64_t z) {
  return (static_cast<std::uint64_t>(x + kKeyOffset) << (2 * kKeyBits)) |
         (static_cast<std::uint64_t>(y + kKeyOffset) << kKeyBits) |
         static_cast<std::uint64_t>(z + kKeyOffset);
}

inline Eigen::Array3i unpackIndices(std::uint64_t key) {
  return Eigen::Array3i(
      static_cast<int>(static_cast<std::int64_t>((key >> (2 * kKeyBits)) & kKeyMask) - kKeyOffset),
      static_cast<int>(static_cast<std::int64_t>((key >> kKeyBits) & kKeyMask) - kKeyOffset),
      static_cast<int>(static_cast<std::int64_t>(key & kKeyMask) - kKeyOffset));
}

// The floor cell (voxel column) of a voxel key: its x and y indices, z = 0.
inline std::uint64_t columnOf(std::uint64_t key) {
  return (key & ~kKeyMask) | static_cast<std::uint64_t>(kKeyOffset);
}

// Whether p is inside the convex hull (CCW) or within `margin` of its outline.
inline bool insideConvexOrNear(const Eigen::Vector2f& p, const std::vector<Eigen::Vector2f>& hull,
                               float margin) {
  if (hull.size() < 3) return false;
  bool inside = true;
  float nearest = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2f& a = hull[i];
    const Eigen::Vector2f& b = hull[(i + 1) % hull.size()];
    const Eigen::Vector2f ab = b - a, ap = p - a;
    if (ab.x() * ap.y() - ab.y() * ap.x() < 0.0f) inside = false;
    const float len2 = ab.squaredNorm();
    const float t = len2 > 0.0f ? std::clamp(ap.dot(ab) / len2, 0.0f, 1.0f) : 0.0f;
    nearest = std::min(nearest, (a + t * ab - p).norm());
  }
  return inside || nearest <= margin;
}

}  // namespace findmug::semantic_map_detail
