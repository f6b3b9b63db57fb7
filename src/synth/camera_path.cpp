// Camera paths: a robot driving between viewpoints around the tables, its
// head turning to look at the table it visits next.
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/synth/synth.hpp"
#include "synth_internal.hpp"

namespace findmug::synth {

namespace detail {

PlanningGrid::PlanningGrid(const SynthScene& scene, double robot_radius, double cell)
    : cell_(cell),
      nx_(static_cast<int>(std::ceil(scene.room_size.x() / cell))),
      ny_(static_cast<int>(std::ceil(scene.room_size.y() / cell))) {
  free_.assign(static_cast<std::size_t>(nx_) * ny_, 0);
  for (int iy = 0; iy < ny_; ++iy) {
    for (int ix = 0; ix < nx_; ++ix) {
      const Eigen::Vector2d p = centerOf(ix, iy);
      bool ok = p.x() >= robot_radius && p.y() >= robot_radius &&
                p.x() <= scene.room_size.x() - robot_radius &&
                p.y() <= scene.room_size.y() - robot_radius;
      for (const auto& o : scene.obstacles) {
        if (!ok) break;
        ok = !insideConvex(o.polygon, p, robot_radius);
      }
      free_[index(ix, iy)] = ok ? 1 : 0;
    }
  }
  // 4-connected components of free space.
  component_.assign(free_.size(), -1);
  int next = 0;
  std::vector<int> stack;
  for (int start = 0; start < static_cast<int>(free_.size()); ++start) {
    if (!free_[start] || component_[start] >= 0) continue;
    component_[start] = next;
    stack.push_back(start);
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      const int cx = c % nx_, cy = c / nx_;
      const int nbr[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
      for (const auto& d : nbr) {
        const int x = cx + d[0], y = cy + d[1];
        if (x < 0 || y < 0 || x >= nx_ || y >= ny_) continue;
        const int n = index(x, y);
        if (free_[n] && component_[n] < 0) {
          component_[n] = next;
          stack.push_back(n);
        }
      }
    }
    ++next;
  }
}

bool PlanningGrid::cellOf(const Eigen::Vector2d& xy, int& ix, int& iy) const {
  ix = static_cast<int>(std::floor(xy.x() / cell_));
  iy = static_cast<int>(std::floor(xy.y() / cell_));
  return ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_;
}

bool PlanningGrid::freeAt(const Eigen::Vector2d& xy) const {
  int ix, iy;
  return cellOf(xy, ix, iy) && free_[index(ix, iy)];
}

int PlanningGrid::componentAt(const Eigen::Vector2d& xy) const {
  int ix, iy;
  return cellOf(xy, ix, iy) ? component_[index(ix, iy)] : -1;
}

bool PlanningGrid::lineFree(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  const double len = (b - a).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(len / (0.5 * cell_))));
  for (int s = 0; s <= steps; ++s)
    if (!freeAt(a + (b - a) * (static_cast<double>(s) / steps))) return false;
  return true;
}

std::vector<Eigen::Vector2d> PlanningGrid::path(const Eigen::Vector2d& from,
                                                const Eigen::Vector2d& to) const {
  int sx, sy, gx, gy;
  if (!cellOf(from, sx, sy) || !cellOf(to, gx, gy)) return {};
  const int start = index(sx, sy), goal = index(gx, gy);
  if (!free_[start] || !free_[goal] || component_[start] != component_[goal]) return {};
  // Dijkstra on the 8-connected grid (small: a few ten thousand cells).
  std::vector<double> dist(free_.size(), std::numeric_limits<double>::infinity());
  std::vector<int> parent(free_.size(), -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  dist[start] = 0.0;
  open.push({0.0, start});
  while (!open.empty()) {
    const auto [d, c] = open.top();
    open.pop();
    if (d > dist[c]) continue;
    if (c == goal) break;
    const int cx = c % nx_, cy = c / nx_;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy) continue;
        const int x = cx + dx, y = cy + dy;
        if (x < 0 || y < 0 || x >= nx_ || y >= ny_) continue;
        const int n = index(x, y);
        // Diagonal moves must not cut a blocked corner.
        if (!free_[n] || !free_[index(cx + dx, cy)] || !free_[index(cx, cy + dy)]) continue;
        const double nd = d + ((dx && dy) ? M_SQRT2 : 1.0);
        if (nd < dist[n]) {
          dist[n] = nd;
          parent[n] = c;
          open.push({nd, n});
        }
      }
    }
  }
  std::vector<Eigen::Vector2d> cells;
  for (int c = goal; c >= 0; c = parent[c]) cells.push_back(centerOf(c % nx_, c / nx_));
  std::reverse(cells.begin(), cells.end());
  cells.front() = from;
  cells.back() = to;
  // String pulling: jump to the furthest cell in sight.
  std::vector<Eigen::Vector2d> out{from};
  std::size_t i = 0;
  while (i + 1 < cells.size()) {
    std::size_t j = cells.size() - 1;
    while (j > i + 1 && !lineFree(cells[i], cells[j])) --j;
    out.push_back(cells[j]);
    i = j;
  }
  return out;
}

std::vector<Viewpoint> findViewpoints(const SynthScene& scene, const PlanningGrid& grid,
                                      double camera_height, double pitch,
                                      const CameraPathParams& params, int per_table, Rng& rng) {
  std::vector<Viewpoint> all;
  for (const auto& t : scene.tables) {
    // Ground distance that centres the table top in the image.
    const double drop = camera_height - t.height;
    const double desired = drop > 0.05 ? drop / std::tan(pitch) : 1.0;
    struct Candidate {
      Eigen::Vector2d xy;
      double angle, score;
    };
    std::vector<Candidate> candidates;
    const double a0 = rng.uniform(0.0, 2.0 * M_PI);
    for (int k = 0; k < 36; ++k) {
      const double a = a0 + 2.0 * M_PI * k / 36;
      const Eigen::Vector2d dir(std::cos(a), std::sin(a));
      for (double d = 0.3; d <= params.max_view_distance_m; d += 0.05) {
        const Eigen::Vector2d p = t.center_xy + d * dir;
        if (!grid.freeAt(p)) continue;
        // Nothing taller than the table may stand between the robot and it.
        bool visible = true;
        for (double s = 0.0; s < 1.0 && visible; s += 0.05 / d) {
          const Eigen::Vector2d q = p + s * (t.center_xy - p);
          for (const auto& o : scene.obstacles) {
            if (o.object == t.object || scene.objects[o.object].label == Label::Chair) continue;
            if (o.top_z > t.height + 0.05 && insideConvex(o.polygon, q)) {
              visible = false;
              break;
            }
          }
        }
        if (visible) candidates.push_back({p, a, std::abs(d - desired) + 0.2 * rng.uniform()});
      }
    }
    if (candidates.empty()) continue;
    std::sort(candidates.begin(), candidates.end(),
              [](const Candidate& x, const Candidate& y) { return x.score < y.score; });
    std::vector<Candidate> chosen{candidates.front()};
    for (const auto& c : candidates) {
      if (static_cast<int>(chosen.size()) >= per_table) break;
      bool apart = true;  // a different side of the table
      for (const auto& h : chosen)
        apart = apart && std::abs(wrapAngle(c.angle - h.angle)) > M_PI / 2;
      if (apart) chosen.push_back(c);
    }
    for (const auto& c : chosen) all.push_back({c.xy, t.id, grid.componentAt(c.xy)});
  }
  if (all.empty()) return all;
  // Keep the free-space region holding the most viewpoints (first one on ties).
  std::vector<int> count;
  for (const auto& v : all) {
    if (v.component >= static_cast<int>(count.size())) count.resize(v.component + 1, 0);
    ++count[v.component];
  }
  int best = all.front().component;
  for (int c = 0; c < static_cast<int>(count.size()); ++c)
    if (count[c] > count[best]) best = c;
  std::vector<Viewpoint> kept;
  for (const auto& v : all)
    if (v.component == best) kept.push_back(v);
  return kept;
}

bool hasReachableTable(const SynthScene& scene) {
  const CameraPathParams params;
  const PlanningGrid grid(scene, params.robot_radius_m);
  Rng rng(1);
  return !findViewpoints(scene, grid, 1.2, 0.55, params, 1, rng).empty();
}

}  // namespace detail

void validate(const CameraPathParams& p) {
  auto bad = [](const char* what, double value) {
    std::ostringstream msg;
    msg << "synth: camera path " << what << " = " << value << " is out of range";
    throw Error(msg.str());
  };
  if (!(p.height_min >= 0.3 && p.height_min <= p.height_max && p.height_max <= 2.0))
    bad("height range (0.3..2.0 m, min <= max), height_min", p.height_min);
  if (!(p.pitch_min_deg >= 0.0 && p.pitch_min_deg <= p.pitch_max_deg && p.pitch_max_deg <= 80.0))
    bad("pitch range (0..80 deg, min <= max), pitch_min_deg", p.pitch_min_deg);
  if (!(p.speed_mps > 0.0 && p.speed_mps <= 3.0)) bad("speed_mps", p.speed_mps);
  if (!(p.max_yaw_rate > 0.0 && p.max_yaw_rate <= 10.0)) bad("max_yaw_rate", p.max_yaw_rate);
  if (!(p.dwell_s >= 0.0 && p.dwell_s <= 60.0)) bad("dwell_s", p.dwell_s);
  if (!(std::abs(p.pan_amplitude_rad) <= 1.0)) bad("pan_amplitude_rad", p.pan_amplitude_rad);
  if (!(p.robot_radius_m >= 0.05 && p.robot_radius_m <= 1.0))
    bad("robot_radius_m", p.robot_radius_m);
  if (!(p.max_view_distance_m >= 0.5 && p.max_view_distance_m <= 10.0))
    bad("max_view_distance_m", p.max_view_distance_m);
}

std::vector<CameraPose> cameraPath(const SynthScene& scene, int n_frames, double fps,
                                   const CameraPathParams& params) {
  validate(params);
  if (n_frames < 0 || n_frames > 10000000)
    throw Error("synth: absurd frame count " + std::to_string(n_frames));
  if (!(std::isfinite(fps) && fps > 0.0 && fps <= 1000.0))
    throw Error("synth: absurd frame rate " + std::to_string(fps));
  detail::Rng rng(detail::hash3(scene.seed, 0xca3e7a, 1));
  const double height = rng.uniform(params.height_min, params.height_max);
  const double pitch = rng.uniform(params.pitch_min_deg, params.pitch_max_deg) * M_PI / 180.0;
  const detail::PlanningGrid grid(scene, params.robot_radius_m);
  const auto viewpoints = detail::findViewpoints(scene, grid, height, pitch, params, 2, rng);
  if (viewpoints.empty())
    throw Error("synth: no table of scene seed " + std::to_string(scene.seed) +
                " can be seen from free floor (robot radius " +
                std::to_string(params.robot_radius_m) + " m)");

  auto bearing = [&](const Eigen::Vector2d& from, int table) {
    const Eigen::Vector2d d = scene.tables[table].center_xy - from;
    return std::atan2(d.y(), d.x());
  };
  const double dt = 1.0 / fps;
  const int m = static_cast<int>(viewpoints.size());
  Eigen::Vector2d pos = viewpoints[0].xy;
  double yaw = bearing(pos, viewpoints[0].table);
  int at = 0;  // viewpoint we are at (dwelling) or came from (moving)
  bool moving = false;
  double phase_time = 0.0;
  std::vector<Eigen::Vector2d> route;  // remaining polyline while moving
  std::size_t route_next = 0;

  std::vector<CameraPose> poses;
  poses.reserve(n_frames);
  for (int i = 0; i < n_frames; ++i) {
    CameraPose pose;
    pose.xy = pos;
    const double pan =
        moving || params.dwell_s <= 0.0
            ? 0.0
            : params.pan_amplitude_rad * std::sin(2.0 * M_PI * phase_time / params.dwell_s);
    pose.yaw = detail::wrapAngle(yaw + pan);
    pose.height_m = height;
    pose.pitch_rad = pitch;
    pose.roll_rad = 0.0;
    pose.time_s = i * dt;
    poses.push_back(pose);

    // Advance the robot by one frame.
    phase_time += dt;
    if (!moving && m > 1 && phase_time >= params.dwell_s) {
      route = grid.path(pos, viewpoints[(at + 1) % m].xy);
      route_next = 1;
      moving = route.size() >= 2;
      phase_time = 0.0;
    }
    if (moving) {
      double step = params.speed_mps * dt;
      while (step > 0.0 && route_next < route.size()) {
        const Eigen::Vector2d d = route[route_next] - pos;
        const double len = d.norm();
        if (len <= step) {
          pos = route[route_next++];
          step -= len;
        } else {
          pos += d * (step / len);
          step = 0.0;
        }
      }
      if (route_next >= route.size()) {
        moving = false;
        at = (at + 1) % m;
        phase_time = 0.0;
      }
    }
    const int target = moving ? viewpoints[(at + 1) % m].table : viewpoints[at].table;
    const double turn = detail::wrapAngle(bearing(pos, target) - yaw);
    const double max_turn = params.max_yaw_rate * dt;
    yaw = detail::wrapAngle(yaw + std::clamp(turn, -max_turn, max_turn));
  }
  return poses;
}

Eigen::Isometry3d cameraToWorld(const CameraPose& pose) {
  Eigen::Matrix3d r0;  // optical (x right, y down, z forward) -> level (x fwd, y left, z up)
  r0.col(0) = Eigen::Vector3d(0, -1, 0);
  r0.col(1) = Eigen::Vector3d(0, 0, -1);
  r0.col(2) = Eigen::Vector3d(1, 0, 0);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
               Eigen::AngleAxisd(pose.pitch_rad, Eigen::Vector3d::UnitY()).toRotationMatrix() * r0 *
               Eigen::AngleAxisd(pose.roll_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(pose.xy.x(), pose.xy.y(), pose.height_m);
  return t;
}

Eigen::Isometry3d worldToGround(const CameraPose& pose) {
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.linear() = Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  base.translation() = Eigen::Vector3d(pose.xy.x(), pose.xy.y(), 0.0);
  return base.inverse();
}

CameraExtrinsics extrinsicsOf(const CameraPose& pose) {
  return {pose.height_m, pose.pitch_rad, pose.roll_rad};
}

TableTruth tableInGroundFrame(const TableTruth& table, const CameraPose& pose) {
  const Eigen::Isometry3d w2g = worldToGround(pose);
  auto xy = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d((w2g * Eigen::Vector3d(p.x(), p.y(), 0.0)).head<2>());
  };
  TableTruth out = table;
  out.center_xy = xy(table.center_xy);
  out.yaw = detail::wrapAngle(table.yaw - pose.yaw);
  for (auto& v : out.top_polygon) v = xy(v);
  return out;
}

double signedDistanceToTop(const TableTruth& table, const Eigen::Vector2d& xy) {
  const auto& poly = table.top_polygon;
  if (poly.size() < 3)
    throw Error("synth: table " + std::to_string(table.id) + " has no top polygon");
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d a = poly[i], e = poly[(i + 1) % poly.size()] - a;
    const double s = std::clamp((xy - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + s * e - xy).norm());
  }
  return detail::insideConvex(poly, xy) ? -best : best;
}

}  // namespace findmug::synth
