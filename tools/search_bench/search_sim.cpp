// The simulated robot of findmug-search-bench: occupancy grid and planner, episode worlds,
// the oracle recogniser and the time accounting of the base (see search_sim.hpp).
#include "search_sim.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <queue>

#include "findmug/common/error.hpp"

namespace findmug::search {

namespace {

// A mixed seed as a uniform number in [0, 1).
double unit(std::uint64_t bits) { return (bits >> 11) * 0x1.0p-53; }

// Into [-pi, pi]. An angle that is not finite, or so large that subtracting 2 pi no longer
// changes it, is refused: the loop below never ended on one (a heading of 7.8e26 rad, read
// from a freed answer by the look-closer step before d51ad03, reached Robot::turnTo once).
double wrap(double a) {
  if (!(std::abs(a) < 1e6)) {
    char what[96];
    std::snprintf(what, sizeof what, "search sim: an angle of %g rad is not a heading", a);
    throw Error(what);
  }
  while (a > M_PI) a -= 2.0 * M_PI;
  while (a < -M_PI) a += 2.0 * M_PI;
  return a;
}

// Point inside a convex CCW polygon grown by `margin` (the renderer's test, restated here:
// the synth library keeps its helpers internal).
bool insideGrown(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p,
                 double margin) {
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d e = poly[(i + 1) % n] - poly[i];
    const double cross = e.x() * (p.y() - poly[i].y()) - e.y() * (p.x() - poly[i].x());
    if (cross < -margin * e.norm()) return false;
  }
  return true;
}

synth::RenderOptions oracleRender() {
  synth::RenderOptions options;
  options.noise.enabled = false;  // object indices do not depend on the noise
  return options;
}

// The first cell (in order of planned distance from the start) from which the mug is
// recognised, on a 0.15 m lattice within range of the mug; -1 when none.
int nearestRecognisingCell(const World& w, const SimParams& params, const std::vector<double>& dist,
                           double& yaw_out) {
  const Eigen::Vector2d mug = w.mug.position.head<2>();
  const int stride = std::max(1, static_cast<int>(std::lround(0.15 / w.grid.cell())));
  std::vector<std::pair<double, int>> candidates;
  for (int i = 0; i < w.grid.size(); ++i) {
    if (!std::isfinite(dist[i])) continue;
    if ((i % w.grid.nx()) % stride != 0 || (i / w.grid.nx()) % stride != 0) continue;
    if (mugInRange(w, params, w.grid.center(i))) candidates.push_back({dist[i], i});
  }
  std::sort(candidates.begin(), candidates.end());
  for (const auto& [d, i] : candidates) {
    const Eigen::Vector2d to = mug - w.grid.center(i);
    const double yaw = std::atan2(to.y(), to.x());
    if (mugRecognisable(w, params, w.grid.center(i), yaw)) {
      yaw_out = yaw;
      return i;
    }
  }
  return -1;
}

// A uniformly drawn free cell of the largest free-space region reachable from a room's
// centre (rooms can hold small pockets walled in by furniture; the robot starts outside
// them), in another room than `avoid_room`.
int drawStartCell(const Grid& grid, const synth::MultiRoomApartment& apt, int avoid_room,
                  std::uint64_t seed) {
  std::vector<int> best;
  for (std::size_t r = 0; r < apt.rooms.size(); ++r) {
    const int c = grid.nearestFree(apt.rooms[r].center(), 2.0);
    if (c < 0) continue;
    const std::vector<double> dist = grid.distancesFrom(c);
    std::vector<int> reachable;
    for (int i = 0; i < grid.size(); ++i)
      if (std::isfinite(dist[i])) reachable.push_back(i);
    if (reachable.size() > best.size()) best = std::move(reachable);
  }
  // A search starts away from the mug: outside its room, when the region reaches another.
  std::vector<int> elsewhere;
  for (int c : best) {
    const int room = apt.roomAt(grid.center(c));
    if (room >= 0 && room != avoid_room) elsewhere.push_back(c);
  }
  if (!elsewhere.empty()) best = std::move(elsewhere);
  if (best.empty())
    throw Error("search: no free start cell in apartment " + std::to_string(apt.scene.seed));
  return best[mix(seed) % best.size()];
}

}  // namespace

// ---- Grid ----------------------------------------------------------------------------

Grid::Grid(const synth::SynthScene& scene, double robot_radius, double cell)
    : cell_(cell),
      nx_(static_cast<int>(std::ceil(scene.room_size.x() / cell))),
      ny_(static_cast<int>(std::ceil(scene.room_size.y() / cell))) {
  free_.assign(static_cast<std::size_t>(nx_) * ny_, 0);
  for (int i = 0; i < size(); ++i) {
    const Eigen::Vector2d p = center(i);
    bool ok = p.x() >= robot_radius && p.y() >= robot_radius &&
              p.x() <= scene.room_size.x() - robot_radius &&
              p.y() <= scene.room_size.y() - robot_radius;
    for (std::size_t o = 0; ok && o < scene.obstacles.size(); ++o)
      ok = !insideGrown(scene.obstacles[o].polygon, p, robot_radius);
    free_[i] = ok ? 1 : 0;
  }
}

int Grid::cellAt(const Eigen::Vector2d& xy) const {
  const int ix = static_cast<int>(std::floor(xy.x() / cell_));
  const int iy = static_cast<int>(std::floor(xy.y() / cell_));
  return ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_ ? iy * nx_ + ix : -1;
}

int Grid::nearestFree(const Eigen::Vector2d& xy, double max_m) const {
  const int r = static_cast<int>(std::ceil(max_m / cell_));
  const int cx = static_cast<int>(std::floor(xy.x() / cell_));
  const int cy = static_cast<int>(std::floor(xy.y() / cell_));
  int best = -1;
  double best_d = kInfinity;
  for (int y = std::max(0, cy - r); y <= std::min(ny_ - 1, cy + r); ++y)
    for (int x = std::max(0, cx - r); x <= std::min(nx_ - 1, cx + r); ++x) {
      const int i = y * nx_ + x;
      const double d = (center(i) - xy).norm();
      if (free_[i] && d <= max_m && d < best_d) best = i, best_d = d;
    }
  return best;
}

std::vector<double> Grid::distancesFrom(int start) const {
  std::vector<double> dist(free_.size(), kInfinity);
  if (start < 0 || !free_[start]) return dist;
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  dist[start] = 0.0;
  open.push({0.0, start});
  while (!open.empty()) {
    const auto [d, c] = open.top();
    open.pop();
    if (d > dist[c]) continue;
    const int cx = c % nx_, cy = c / nx_;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = cx + dx, y = cy + dy;
        if ((!dx && !dy) || x < 0 || y < 0 || x >= nx_ || y >= ny_) continue;
        const int n = y * nx_ + x;
        // Diagonal moves must not cut a blocked corner.
        if (!free_[n] || !free_[cy * nx_ + x] || !free_[y * nx_ + cx]) continue;
        const double nd = d + cell_ * ((dx && dy) ? M_SQRT2 : 1.0);
        if (nd < dist[n]) dist[n] = nd, open.push({nd, n});
      }
  }
  return dist;
}

bool Grid::lineFree(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / (0.5 * cell_))));
  for (int s = 0; s <= steps; ++s) {
    const int c = cellAt(a + (b - a) * (static_cast<double>(s) / steps));
    if (c < 0 || !free_[c]) return false;
  }
  return true;
}

std::vector<Eigen::Vector2d> Grid::path(int from, int to) const {
  if (from < 0 || to < 0 || !free_[from] || !free_[to]) return {};
  std::vector<double> g(free_.size(), kInfinity);
  std::vector<int> parent(free_.size(), -1);
  const Eigen::Vector2d goal = center(to);
  auto h = [&](int c) {  // octile distance: admissible on the 8-connected grid
    const double dx = std::abs(center(c).x() - goal.x()), dy = std::abs(center(c).y() - goal.y());
    return std::max(dx, dy) + (M_SQRT2 - 1.0) * std::min(dx, dy);
  };
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  g[from] = 0.0;
  open.push({h(from), from});
  while (!open.empty()) {
    const auto [f, c] = open.top();
    open.pop();
    if (c == to) break;
    if (f - h(c) > g[c] + 1e-9) continue;
    const int cx = c % nx_, cy = c / nx_;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = cx + dx, y = cy + dy;
        if ((!dx && !dy) || x < 0 || y < 0 || x >= nx_ || y >= ny_) continue;
        const int n = y * nx_ + x;
        if (!free_[n] || !free_[cy * nx_ + x] || !free_[y * nx_ + cx]) continue;
        const double ng = g[c] + cell_ * ((dx && dy) ? M_SQRT2 : 1.0);
        if (ng < g[n]) g[n] = ng, parent[n] = c, open.push({ng + h(n), n});
      }
  }
  if (!std::isfinite(g[to])) return {};
  std::vector<Eigen::Vector2d> cells;
  for (int c = to; c >= 0; c = parent[c]) cells.push_back(center(c));
  std::reverse(cells.begin(), cells.end());
  // String pulling: jump to the furthest cell in sight (never longer than the grid path).
  std::vector<Eigen::Vector2d> out{cells.front()};
  std::size_t i = 0;
  while (i + 1 < cells.size()) {
    std::size_t j = cells.size() - 1;
    while (j > i + 1 && !lineFree(cells[i], cells[j])) --j;
    out.push_back(cells[j]);
    i = j;
  }
  return out;
}

// ---- worlds and the recogniser --------------------------------------------------------

synth::CameraPose cameraAt(const SimParams& params, const Eigen::Vector2d& xy, double yaw) {
  synth::CameraPose pose;
  pose.xy = xy;
  pose.yaw = yaw;
  pose.height_m = params.camera_height_m;
  pose.pitch_rad = params.camera_pitch_rad;
  return pose;
}

int mugPixels(const World& world, const synth::RenderedFrame& frame) {
  int n = 0;
  for (const std::int32_t object : frame.object) n += object == world.mug.object;
  return n;
}

bool mugInRange(const World& world, const SimParams& params, const Eigen::Vector2d& xy) {
  const Eigen::Vector3d camera(xy.x(), xy.y(), params.camera_height_m);
  const Eigen::Vector3d mug = world.mug.position + Eigen::Vector3d(0, 0, world.mug.height / 2);
  return (mug - camera).norm() <= params.recognise_range_m;
}

bool mugRecognisable(const World& world, const SimParams& params, const Eigen::Vector2d& xy,
                     double yaw) {
  if (!mugInRange(world, params, xy)) return false;
  // Well outside the horizontal field of view (half angle atan(320 / 525) = 0.547 rad, plus
  // the mug's own angular size and a margin) no pixel can count: skip the render.
  const Eigen::Vector2d to = world.mug.position.head<2>() - xy;
  const double d = std::max(to.norm(), 0.1);
  const double half_width = std::asin(std::min(1.0, 0.08 / d));
  if (std::abs(wrap(std::atan2(to.y(), to.x()) - yaw)) > 0.547 + half_width + 0.05) return false;
  // The mug's pixels only, not a whole frame: countObjectPixels equals the count in the
  // rendered frame's object index (test ObjectPixelCountEqualsTheRenderedFrames).
  static const synth::RenderOptions options = oracleRender();
  return synth::countObjectPixels(world.apartment.scene, cameraAt(params, xy, yaw), options,
                                  world.mug.object) >= params.recognise_min_pixels;
}

World makeWorld(const Episode& episode, const SimParams& params) {
  const synth::MultiRoomApartment base =
      synth::makeMultiRoomApartment(episode.apartment_seed, params.apartment);
  for (int attempt = 0; attempt < 10; ++attempt) {
    World w;
    w.episode = episode;
    w.apartment = base;
    w.mug =
        synth::placeTargetMug(w.apartment, mix(episode.episode_seed + 977 * attempt), params.prior,
                              params.look_alikes);
    w.grid = Grid(w.apartment.scene, params.robot_radius_m, params.cell_m);
    const int start =
        drawStartCell(w.grid, w.apartment, w.mug.room, mix(episode.episode_seed ^ 0x5747ULL));
    w.start = w.grid.center(start);
    w.start_yaw = 2.0 * M_PI * unit(mix(episode.episode_seed ^ 0x9a3ULL)) - M_PI;
    const std::vector<double> dist = w.grid.distancesFrom(start);
    const int best = nearestRecognisingCell(w, params, dist, w.best_view_yaw);
    if (best < 0) continue;
    w.best_view = w.grid.center(best);
    // What the robot drives (the string-pulled A* path), so no strategy beats it.
    const std::vector<Eigen::Vector2d> path = w.grid.path(start, best);
    w.shortest_path_m = 0.0;
    for (std::size_t i = 1; i < path.size(); ++i)
      w.shortest_path_m += (path[i] - path[i - 1]).norm();
    return w;
  }
  throw Error("search: no recognisable mug placement for episode seed " +
              std::to_string(episode.episode_seed));
}

// ---- what the frames have shown --------------------------------------------------------

ViewCoverage::ViewCoverage(const World& world, const SimParams& params)
    : grid_(&world.grid),
      range_m_(params.look_coverage_range_m),
      seen_(world.grid.size(), 0),
      blocks_(world.grid.size(), 0),
      stamp_(world.grid.size(), 0) {
  for (int i = 0; i < world.grid.size(); ++i) {
    const Eigen::Vector2d p = world.grid.center(i);
    for (const synth::Obstacle& o : world.apartment.scene.obstacles) {
      if (o.top_z <= params.camera_height_m - 0.2) continue;  // the camera looks over it
      if (insideGrown(o.polygon, p, 0.0)) {
        blocks_[i] = 1;
        break;
      }
    }
  }
}

template <typename Visit>
void ViewCoverage::castFrame(const Eigen::Vector2d& xy, double yaw, double range_m,
                             double half_angle, Visit&& visit) const {
  if (grid_ == nullptr) return;
  const double step = 0.5 * grid_->cell();
  // Rays no further apart than half a cell at the range: every cell in view is hit.
  const int rays = static_cast<int>(std::ceil(2.0 * half_angle * range_m / step)) + 1;
  if (++casts_ == 0) std::fill(stamp_.begin(), stamp_.end(), 0), casts_ = 1;
  for (int k = 0; k < rays; ++k) {
    const double a = yaw - half_angle + 2.0 * half_angle * k / (rays - 1);
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    for (double r = 0.0; r <= range_m; r += step) {
      const int c = grid_->cellAt(xy + r * dir);
      if (c < 0 || blocks_[c]) break;
      if (stamp_[c] == casts_) continue;
      stamp_[c] = casts_;
      visit(c);
    }
  }
}

void ViewCoverage::markFrame(const Eigen::Vector2d& xy, double yaw) {
  castFrame(xy, yaw, range_m_, kCameraHalfFov, [this](int c) { seen_[c] = 1; });
}

double ViewCoverage::unseenM2(const Eigen::Vector2d& xy, double yaw) const {
  if (grid_ == nullptr) return 0.0;
  int unseen = 0;
  castFrame(xy, yaw, range_m_, kCameraHalfFov, [&](int c) { unseen += seen_[c] == 0; });
  return unseen * grid_->cell() * grid_->cell();
}

std::vector<int> ViewCoverage::cellsInViewAround(const Eigen::Vector2d& xy, double range_m) const {
  std::vector<int> cells;
  castFrame(xy, 0.0, range_m, M_PI, [&cells](int c) { cells.push_back(c); });
  return cells;
}

// ---- the robot ------------------------------------------------------------------------

bool claimIsCorrect(const World& world, const Eigen::Vector3d& reported, double tolerance_m) {
  return (reported.head<2>() - world.mug.position.head<2>()).norm() <= tolerance_m;
}

Robot::Robot(const World& world, const SimParams& params, FrameHook on_frame,
             Recognition recognition)
    : world_(world),
      params_(params),
      on_frame_(std::move(on_frame)),
      recognition_(recognition),
      xy_(world.start),
      yaw_(world.start_yaw),
      coverage_(world, params) {
  if (recognition_ == Recognition::Matcher && !on_frame_)
    throw Error("search: matcher recognition needs the daemon's frames (no frame hook)");
  if (params_.trace) {
    char line[160];
    std::snprintf(line, sizeof line, "the mug at (%.2f, %.2f, %.2f), on furniture %d, room %d",
                  world.mug.position.x(), world.mug.position.y(), world.mug.position.z(),
                  world.mug.furniture, world.mug.room);
    note(line);
    for (std::size_t r = 0; r < world.apartment.rooms.size(); ++r) {
      const synth::RoomTruth& room = world.apartment.rooms[r];
      std::snprintf(line, sizeof line, "room %zu (%s): (%.2f, %.2f) to (%.2f, %.2f)", r,
                    synth::roomKindName(room.kind), room.lo.x(), room.lo.y(), room.hi.x(),
                    room.hi.y());
      note(line);
    }
    if (world.mug.furniture >= 0) {
      const synth::FurnitureTruth& f = world.apartment.furniture[world.mug.furniture];
      std::string corners;
      for (const Eigen::Vector2d& v : f.footprint) {
        std::snprintf(line, sizeof line, " (%.2f, %.2f)", v.x(), v.y());
        corners += line;
      }
      note("the mug's " + f.kind + ": footprint" + corners);
    }
  }
}

void Robot::spend(double seconds) { stats_.time_s += seconds; }

void Robot::note(const std::string& what) {
  if (!params_.trace) return;
  char head[64];
  std::snprintf(head, sizeof head, "%7.1f s  (%5.2f, %5.2f) %4.0f deg  ", stats_.time_s, xy_.x(),
                xy_.y(), yaw_ * 180.0 / M_PI);
  trace_.push_back(head + what);
}

bool Robot::move(double seconds, const Eigen::Vector2d& to_xy, double to_yaw, bool turning) {
  const Eigen::Vector2d from_xy = xy_;
  const double from_yaw = yaw_, length = (to_xy - from_xy).norm();
  const RunStats before = stats_;
  const double m0 = motion_s_;
  // The pose and the books a fraction `f` of the way through the motion.
  auto at = [&](double f) {
    const double dt = f * seconds;
    (turning ? stats_.turn_s : stats_.drive_s) = (turning ? before.turn_s : before.drive_s) + dt;
    stats_.path_m = before.path_m + f * length;
    stats_.time_s = before.time_s + dt;
    motion_s_ = m0 + dt;
    xy_ = f >= 1.0 ? to_xy : Eigen::Vector2d(from_xy + f * (to_xy - from_xy));
    yaw_ = wrap(from_yaw + f * (to_yaw - from_yaw));
  };
  if (params_.drive_frames_hz > 0.0 && seconds > 0.0) {
    // Frames fall on multiples of the period of motion time, so a run of short motions
    // (a look-around's turns) gets them at the same rate as one long one.
    const double period = 1.0 / params_.drive_frames_hz;
    for (auto k = static_cast<long long>(std::floor(m0 / period)) + 1; k * period <= m0 + seconds;
         ++k) {
      const double dt = k * period - m0;
      if (before.time_s + dt > params_.time_budget_s) break;
      at(dt / seconds);
      ++stats_.drive_frames;
      if (perceive(false)) return false;
      if (stop_when_ != nullptr && (*stop_when_)()) {
        interrupted_ = true;  // the robot stops where the frame was taken
        return false;
      }
    }
  }
  at(1.0);
  return true;
}

void Robot::turnTo(double yaw) {
  if (!active()) return;
  const double delta = wrap(yaw - yaw_);
  move(std::abs(delta) / params_.turn_rate_rad_s, xy_, yaw_ + delta, true);
}

void Robot::turnBy(double delta) {
  if (!active()) return;
  move(std::abs(delta) / params_.turn_rate_rad_s, xy_, yaw_ + delta, true);
}

int Robot::cell() const {
  const int own = world_.grid.cellAt(xy_);
  if (own >= 0 && world_.grid.free(own)) return own;
  const int near = world_.grid.nearestFree(xy_, 0.25);
  return near >= 0 ? near : own;
}

bool Robot::driveTo(const Eigen::Vector2d& goal, const std::function<bool()>& stop_when) {
  interrupted_ = false;
  if (!active()) return false;
  const int to = world_.grid.nearestFree(goal, 0.5);
  const std::vector<Eigen::Vector2d> path = world_.grid.path(cell(), to);
  if (path.empty()) return false;
  if (params_.trace) {
    double length = 0.0;
    for (std::size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
    char line[96];
    std::snprintf(line, sizeof line, "drive to (%.2f, %.2f), %.1f m", goal.x(), goal.y(), length);
    note(line);
  }
  stop_when_ = stop_when ? &stop_when : nullptr;
  for (std::size_t i = 1; i < path.size() && active(); ++i) {
    const Eigen::Vector2d leg = path[i] - xy_;
    if (leg.norm() < 1e-9) continue;
    turnTo(std::atan2(leg.y(), leg.x()));
    if (!active() || interrupted_) break;
    if (!move(leg.norm() / params_.speed_mps, path[i], yaw_, false)) break;
  }
  stop_when_ = nullptr;
  if (interrupted_) note("stopped: something new to look at");
  return true;
}

bool Robot::perceive(bool stop_view) {
  ++stats_.recogniser_calls;
  coverage_.markFrame(xy_, yaw_);
  bool claimed = false;
  Eigen::Vector3d reported = world_.mug.position;
  if (on_frame_) {
    // Noise differs per frame; the object index (what the oracle reads) does not.
    ++frames_;
    const synth::RenderedFrame frame =
        synth::render(world_.apartment.scene, cameraAt(params_, xy_, yaw_), synth::RenderOptions{},
                      mix(world_.episode.episode_seed * 1315423911ULL + frames_));
    const Sighting sighting = on_frame_(frame, xy_, yaw_, stats_.time_s);
    for (const std::string& line : sighting.notes) note(line);
    if (recognition_ == Recognition::Matcher) {
      claimed = sighting.claimed;
      reported = sighting.reported;
    } else {
      claimed = mugInRange(world_, params_, xy_) &&
                mugPixels(world_, frame) >= params_.recognise_min_pixels;
    }
  } else {
    claimed = mugRecognisable(world_, params_, xy_, yaw_);
  }
  if (!claimed) return false;
  // A driving frame's answer comes after its processing, which overlapped the motion: the
  // robot stops where the frame was taken, that much later.
  const double when = stats_.time_s + (stop_view ? 0.0 : params_.view_processing_s);
  if (when > params_.time_budget_s) return false;
  if (!stop_view) stats_.process_s += params_.view_processing_s;
  stats_.time_s = when;
  stats_.found_time_s = when;
  if (recognition_ == Recognition::Oracle ||
      claimIsCorrect(world_, reported, params_.found_tolerance_m))
    stats_.found = true;
  else
    stats_.false_found = true;
  // Where perception put it: what a false "found" took for the mug.
  char where[96];
  std::snprintf(where, sizeof(where), " at (%.2f, %.2f, %.2f), %.2f m from the mug", reported.x(),
                reported.y(), reported.z(),
                (reported.head<2>() - world_.mug.position.head<2>()).norm());
  note(std::string(stats_.found ? "found" : "false found") +
       (stop_view ? " (stop view)" : " (driving frame)") + where);
  return true;
}

bool Robot::look() {
  if (!active()) return false;
  stats_.process_s += params_.view_processing_s;
  spend(params_.view_processing_s);
  ++stats_.views;
  views_.push_back({xy_, yaw_});
  return perceive(true);
}

bool Robot::lookAround(bool only_unseen) {
  const int n = params_.look_around_views;
  const double step = 2.0 * M_PI / n;
  if (!only_unseen || params_.full_look_arounds) {
    note("look around");
    for (int k = 0; k < n && active(); ++k) {
      if (k > 0) turnTo(yaw_ + step);
      if (look()) return true;
    }
    return stats_.found || stats_.false_found;
  }
  // The headings worth a view, as steps from the current heading (0..n-1).
  const double yaw0 = yaw_;
  std::vector<int> wanted;
  for (int k = 0; k < n; ++k)
    if (coverage_.unseenM2(xy_, yaw0 + k * step) >= params_.look_unseen_min_m2) wanted.push_back(k);
  stats_.look_around_views_skipped += n - static_cast<int>(wanted.size());
  // The shortest turn through them: counter-clockwise up to wanted[i - 1] and clockwise
  // down to wanted[i], whichever way first (i = 0: all clockwise; i = m: all
  // counter-clockwise).
  const int m = static_cast<int>(wanted.size());
  int best_split = m;
  bool ccw_first = true;
  double best_turn = kInfinity;
  for (int i = 0; i <= m; ++i) {
    const double ccw = i > 0 ? wanted[i - 1] * step : 0.0;
    // The current heading (wanted[0] == 0) needs no turn either way.
    int j = i;
    while (j < m && wanted[j] == 0) ++j;
    const double cw_part = j < m ? (n - wanted[j]) * step : 0.0;
    for (const bool first_ccw : {true, false}) {
      const double turn = first_ccw ? 2.0 * ccw + cw_part : ccw + 2.0 * cw_part;
      if (turn < best_turn - 1e-9) best_turn = turn, best_split = i, ccw_first = first_ccw;
    }
  }
  // Signed offsets from the heading at the start, in the order the turn reaches them.
  std::vector<double> tour;
  std::vector<double> ccw_part, cw_part;
  for (int i = 0; i < best_split; ++i) ccw_part.push_back(wanted[i] * step);
  for (int i = m - 1; i >= best_split; --i)
    cw_part.push_back(wanted[i] == 0 ? 0.0 : (wanted[i] - n) * step);
  // A heading at offset 0 is taken first, where the robot stands.
  for (auto* part : ccw_first ? std::vector{&ccw_part, &cw_part} : std::vector{&cw_part, &ccw_part})
    tour.insert(tour.end(), part->begin(), part->end());
  std::stable_partition(tour.begin(), tour.end(), [](double o) { return o == 0.0; });
  {
    char line[96];
    std::snprintf(line, sizeof line, "look around: %d of %d headings show something new, %.0f deg",
                  m, n, best_turn * 180.0 / M_PI);
    note(line);
  }
  double at = 0.0;  // the current offset from yaw0
  for (const double offset : tour) {
    if (!active()) break;
    // Frames while turning may have shown it meanwhile: then it needs no stop view.
    if (coverage_.unseenM2(xy_, yaw0 + offset) < params_.look_unseen_min_m2) {
      ++stats_.look_around_views_skipped;
      continue;
    }
    turnBy(offset - at);
    at = offset;
    if (look()) return true;
  }
  return stats_.found || stats_.false_found;
}

}  // namespace findmug::search
