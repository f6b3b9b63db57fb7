// Internal helpers of findmug_synth: a portable deterministic RNG, per-pixel
// hashing and small 2-D polygon geometry. Not part of the public API.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

namespace findmug::synth::detail {

// SplitMix64 finaliser: a good 64-bit mix, used both as the RNG step and as a
// counter-based hash so that a pixel's noise does not depend on render order.
inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

inline std::uint64_t hash3(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return mix64(mix64(mix64(a) ^ b) ^ c);
}

// Uniform in [0, 1) from the top 53 bits.
inline double toUnit(std::uint64_t bits) { return (bits >> 11) * 0x1.0p-53; }

// Deterministic on every platform (std distributions are not).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(mix64(seed ^ 0x5eed5eed5eedULL)) {}
  std::uint64_t next() {
    state_ += 0x9e3779b97f4a7c15ULL;
    return mix64(state_);
  }
  double uniform() { return toUnit(next()); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int integer(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi - lo + 1));
  }
  bool chance(double p) { return uniform() < p; }
  double normal() {  // Box-Muller; speed does not matter at scene generation
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::uint64_t state_;
};

// Standard normal from 64 hash bits via a tabulated inverse CDF with linear
// interpolation (fast enough for one draw per pixel; tails cut at ~3.7 sigma).
double gaussianFromBits(std::uint64_t bits);

using Polygon2 = std::vector<Eigen::Vector2d>;

inline Polygon2 rectangle(const Eigen::Vector2d& center, double yaw, double half_x, double half_y) {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  return {center - half_x * ax - half_y * ay, center + half_x * ax - half_y * ay,
          center + half_x * ax + half_y * ay, center - half_x * ax + half_y * ay};
}

inline Polygon2 circle(const Eigen::Vector2d& center, double radius, int n) {
  Polygon2 poly;
  poly.reserve(n);
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    poly.push_back(center + radius * Eigen::Vector2d(std::cos(a), std::sin(a)));
  }
  return poly;
}

// Point in a convex counter-clockwise polygon, with `margin` metres of slack
// (positive = accept points that far outside).
inline bool insideConvex(const Polygon2& poly, const Eigen::Vector2d& p, double margin = 0.0) {
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[(i + 1) % n];
    const Eigen::Vector2d e = b - a;
    const double cross = e.x() * (p.y() - a.y()) - e.y() * (p.x() - a.x());
    if (cross < -margin * e.norm()) return false;
  }
  return true;
}

// Separating-axis test for two convex polygons.
inline bool convexOverlap(const Polygon2& a, const Polygon2& b) {
  auto separated = [](const Polygon2& p, const Polygon2& q) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Eigen::Vector2d e = p[(i + 1) % p.size()] - p[i];
      const Eigen::Vector2d n(e.y(), -e.x());  // outward for CCW
      double pmax = -1e300, qmin = 1e300;
      for (const auto& v : p) pmax = std::max(pmax, n.dot(v));
      for (const auto& v : q) qmin = std::min(qmin, n.dot(v));
      if (qmin > pmax) return true;
    }
    return false;
  };
  return !separated(a, b) && !separated(b, a);
}

// A floor-plan point lifted to height z.
inline Eigen::Vector3d at(const Eigen::Vector2d& xy, double z) { return {xy.x(), xy.y(), z}; }

inline double wrapAngle(double a) {
  while (a > M_PI) a -= 2.0 * M_PI;
  while (a < -M_PI) a += 2.0 * M_PI;
  return a;
}

}  // namespace findmug::synth::detail

#include "findmug/synth/synth.hpp"

namespace findmug::synth::detail {

// A spot the robot can stand on to look at a table.
struct Viewpoint {
  Eigen::Vector2d xy;
  int table = 0;
  int component = 0;  // connected free-space region of the planning grid
};

// Occupancy grid of the room for a robot of the given radius (cells are
// blocked when within the radius of a wall or an obstacle footprint).
class PlanningGrid {
 public:
  PlanningGrid(const SynthScene& scene, double robot_radius, double cell = 0.05);
  bool freeAt(const Eigen::Vector2d& xy) const;
  int componentAt(const Eigen::Vector2d& xy) const;  // -1 when blocked
  // Shortest 8-connected path between two free points, shortened by line of
  // sight; empty when they are not connected.
  std::vector<Eigen::Vector2d> path(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const;

 private:
  int index(int ix, int iy) const { return iy * nx_ + ix; }
  bool cellOf(const Eigen::Vector2d& xy, int& ix, int& iy) const;
  Eigen::Vector2d centerOf(int ix, int iy) const {
    return {(ix + 0.5) * cell_, (iy + 0.5) * cell_};
  }
  bool lineFree(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  double cell_;
  int nx_, ny_;
  std::vector<std::uint8_t> free_;
  std::vector<int> component_;
};

// Up to `per_table` viewpoints per table, at ground distances that put the
// table top near the image centre for the given camera height and pitch.
std::vector<Viewpoint> findViewpoints(const SynthScene& scene, const PlanningGrid& grid,
                                      double camera_height, double pitch,
                                      const CameraPathParams& params, int per_table, Rng& rng);

// True when at least one table has a viewpoint with the default path params.
bool hasReachableTable(const SynthScene& scene);

}  // namespace findmug::synth::detail
