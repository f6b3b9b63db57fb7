// Scene edits for walks through a changing room (synth.hpp, "edits").
#include <algorithm>
#include <cmath>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/synth/synth.hpp"
#include "synth_internal.hpp"

namespace findmug::synth {

namespace {

void checkTable(const SynthScene& scene, int table) {
  if (table < 0 || table >= static_cast<int>(scene.tables.size())) {
    throw Error("synth: table " + std::to_string(table) + " out of range (the scene has " +
                std::to_string(scene.tables.size()) + " tables)");
  }
}

// The gap between two convex counter-clockwise polygons along the best separating axis
// (a lower bound of their distance; <= 0 when they overlap).
double separation(const detail::Polygon2& a, const detail::Polygon2& b) {
  double best = -1e300;
  auto along = [&best](const detail::Polygon2& p, const detail::Polygon2& q) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Eigen::Vector2d e = p[(i + 1) % p.size()] - p[i];
      if (e.norm() < 1e-12) continue;
      const Eigen::Vector2d n = Eigen::Vector2d(e.y(), -e.x()).normalized();  // outward
      double pmax = -1e300, qmin = 1e300;
      for (const auto& v : p) pmax = std::max(pmax, n.dot(v));
      for (const auto& v : q) qmin = std::min(qmin, n.dot(v));
      best = std::max(best, qmin - pmax);
    }
  };
  along(a, b);
  along(b, a);
  return best;
}

// The table's footprint as the obstacle list has it (round tops: the planner's 16-gon).
const detail::Polygon2& footprintOf(const SynthScene& scene, const TableTruth& t) {
  for (const Obstacle& o : scene.obstacles) {
    if (o.object == t.object) return o.polygon;
  }
  return t.top_polygon;
}

}  // namespace

void moveTable(SynthScene& scene, int table, const Eigen::Vector2d& offset) {
  checkTable(scene, table);
  TableTruth& t = scene.tables[static_cast<std::size_t>(table)];
  const Eigen::Vector3d shift(offset.x(), offset.y(), 0.0);
  // What stands on the top: small objects above it, inside its outline (decided before
  // anything moves).
  std::vector<bool> riding(scene.objects.size(), false);
  for (const Primitive& p : scene.primitives) {
    const SceneObject& o = scene.objects[static_cast<std::size_t>(p.object)];
    if (o.label == Label::Object && p.center.z() > t.height &&
        signedDistanceToTop(t, p.center.head<2>()) < 0.0) {
      riding[static_cast<std::size_t>(p.object)] = true;
    }
  }
  for (Primitive& p : scene.primitives) {
    if (p.object == t.object || riding[static_cast<std::size_t>(p.object)]) p.center += shift;
  }
  t.center_xy += offset;
  for (auto& v : t.top_polygon) v += offset;
  for (Obstacle& o : scene.obstacles) {
    if (o.object != t.object && !riding[static_cast<std::size_t>(o.object)]) continue;
    for (auto& v : o.polygon) v += offset;
  }
}

std::optional<Eigen::Vector2d> freeSpotForTable(const SynthScene& scene, int table,
                                                double clearance_m, double min_move_m) {
  checkTable(scene, table);
  const TableTruth& t = scene.tables[static_cast<std::size_t>(table)];
  const detail::Polygon2& footprint = footprintOf(scene, t);
  std::optional<Eigen::Vector2d> best;
  double best_distance = -1.0;
  const double step = 0.1;
  const int nx = static_cast<int>(std::ceil(scene.room_size.x() / step));
  const int ny = static_cast<int>(std::ceil(scene.room_size.y() / step));
  for (int ix = -nx; ix <= nx; ++ix) {
    for (int iy = -ny; iy <= ny; ++iy) {
      const Eigen::Vector2d offset(ix * step, iy * step);
      const double distance = offset.norm();
      if (distance < min_move_m || distance <= best_distance) continue;
      detail::Polygon2 moved = footprint;
      bool fits = true;
      for (auto& v : moved) {
        v += offset;
        fits = fits && v.x() >= clearance_m && v.y() >= clearance_m &&
               v.x() <= scene.room_size.x() - clearance_m &&
               v.y() <= scene.room_size.y() - clearance_m;
      }
      for (std::size_t k = 0; fits && k < scene.obstacles.size(); ++k) {
        const Obstacle& o = scene.obstacles[k];
        if (o.object == t.object) continue;
        fits = separation(moved, o.polygon) >= clearance_m;
      }
      if (!fits) continue;
      best = offset;
      best_distance = distance;
    }
  }
  return best;
}

}  // namespace findmug::synth
