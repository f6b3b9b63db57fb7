// The search strategies of findmug-search-bench (see strategies.hpp).
#include "strategies.hpp"

#include <algorithm>
#include <cstdio>
#include <functional>
#include <cmath>
#include <memory>
#include <optional>

#include "findmug/common/error.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/map/table_top_views.hpp"

namespace findmug::search {

namespace {

// Among the reachable cells (finite `dist`) within `max_m` of `xy`, the one closest to it.
int reachableCellNear(const Grid& grid, const std::vector<double>& dist, const Eigen::Vector2d& xy,
                      double max_m) {
  const int r = static_cast<int>(std::ceil(max_m / grid.cell()));
  const int c = grid.cellAt(xy);
  if (c < 0) return -1;
  const int cx = c % grid.nx(), cy = c / grid.nx();
  int best = -1;
  double best_d = kInfinity;
  for (int y = std::max(0, cy - r); y <= std::min(grid.ny() - 1, cy + r); ++y)
    for (int x = std::max(0, cx - r); x <= std::min(grid.nx() - 1, cx + r); ++x) {
      const int i = y * grid.nx() + x;
      const double d = (grid.center(i) - xy).norm();
      if (std::isfinite(dist[i]) && d <= max_m && d < best_d) best = i, best_d = d;
    }
  return best;
}

// The reachable cell of `room` nearest its centre, or -1.
int reachableCellInRoom(const Grid& grid, const std::vector<double>& dist,
                        const synth::RoomTruth& room) {
  int best = -1;
  double best_d = kInfinity;
  for (int i = 0; i < grid.size(); ++i) {
    const Eigen::Vector2d p = grid.center(i);
    if (!std::isfinite(dist[i]) || !room.contains(p)) continue;
    const double d = (p - room.center()).norm();
    if (d < best_d) best = i, best_d = d;
  }
  return best;
}

void coverUntilDone(Robot& robot, const World& world, const SimParams& params, bool look_first);

// What stands at `xy` in the ground truth (for traces): the kind of the furniture whose
// footprint holds it, or "nothing".
std::string furnitureAt(const World& world, const Eigen::Vector2f& xy) {
  for (const synth::FurnitureTruth& f : world.apartment.furniture) {
    const std::size_t n = f.footprint.size();
    bool inside = n >= 3;
    for (std::size_t i = 0; i < n && inside; ++i) {
      const Eigen::Vector2d e = f.footprint[(i + 1) % n] - f.footprint[i];
      const Eigen::Vector2d q = xy.cast<double>() - f.footprint[i];
      inside = e.x() * q.y() - e.y() * q.x() >= 0.0;
    }
    if (inside) return f.kind;
  }
  return "nothing";
}

// Trace lines for the tables a frame added to the daemon's map or took from it: where a
// table the search needed was never mapped, or was forgotten.
std::vector<std::string> mapChanges(const World& world, const std::vector<TableCluster>& before,
                                    const std::vector<TableCluster>& after) {
  const auto has = [](const std::vector<TableCluster>& tables, int id) {
    return std::any_of(tables.begin(), tables.end(),
                       [id](const TableCluster& t) { return t.id == id; });
  };
  std::vector<std::string> lines;
  const auto line = [&](const char* what, const TableCluster& t) {
    Eigen::Vector2f lo = Eigen::Vector2f::Constant(1e9f), hi = -lo;
    for (const Eigen::Vector2f& p : t.hull) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    if (t.hull.empty()) lo = hi = Eigen::Vector2f::Zero();
    char text[200];
    std::snprintf(text, sizeof text,
                  "map: table %d %s at (%.2f, %.2f), top %.2f x %.2f m (x, y), %.2f m high, truth %s",
                  t.id, what, t.center.x(), t.center.y(), hi.x() - lo.x(), hi.y() - lo.y(),
                  t.top_height, furnitureAt(world, t.center).c_str());
    lines.emplace_back(text);
  };
  for (const TableCluster& t : after)
    if (!has(before, t.id)) line("confirmed", t);
  for (const TableCluster& t : before)
    if (!has(after, t.id)) line("gone", t);
  return lines;
}

// One run's perception: the daemon, when the strategy (its table map) or the recogniser
// (the matcher) needs it, and the robot that sends it every frame.
class Eyes {
 public:
  Eyes(const Perception& perception, bool table_map)
      : matcher_(perception.kind == Perception::Kind::Matcher), name_(perception.object_name) {
    if (!matcher_ && !table_map) return;
    if (perception.model == nullptr)
      throw Error(std::string("search: ") +
                  (matcher_ ? "matcher perception" : "the findmug strategy") +
                  " needs the daemon's model");
    daemon_ = std::make_unique<FindmugTables>(*perception.model,
                                              matcher_ ? perception.objects_dir : std::string());
  }

  // What the frames showed of the mapped tables' tops within the recogniser's reach.
  void watchTops(const SimParams& params) {
    TableTopViewsConfig config;
    config.range_m = static_cast<float>(matcher_ ? params.top_seen_range_matcher_m
                                                 : params.top_seen_range_oracle_m);
    tops_ = std::make_unique<TableTopViews>(config);
  }
  // The same for a fixed list of tables instead of the daemon's map (the tables strategy:
  // the apartment's true tables).
  void watchTopsOf(std::vector<TableCluster> tables, const SimParams& params) {
    known_tables_ = std::move(tables);
    watchTops(params);
  }
  // The share of the table's top seen so (0 when tops are not watched or it is unknown).
  double topSeen(int table_id) const {
    if (!tops_) return 0.0;
    for (const TableCluster& t : watchedTables())
      if (t.id == table_id) return tops_->seenShare(t);
    return 0.0;
  }

  Robot robot(const World& world, const SimParams& params) {
    if (!daemon_ && !tops_) return Robot(world, params);
    if (!daemon_) {
      // No daemon: the frames only show the known tables' tops (oracle recognition).
      return Robot(
          world, params,
          [this](const synth::RenderedFrame& frame, const Eigen::Vector2d& xy, double yaw, double) {
            observeTops(frame, xy, yaw);
            return Sighting{};
          });
    }
    return Robot(
        world, params,
        [this, &world, trace = params.trace](const synth::RenderedFrame& frame,
                                             const Eigen::Vector2d& xy, double yaw, double t) {
          Sighting sighting;
          std::vector<TableCluster> before;
          if (trace) before = daemon_->mapTables();
          daemon_->feed(frame, xy, yaw, t);
          if (trace) sighting.notes = mapChanges(world, before, daemon_->mapTables());
          observeTops(frame, xy, yaw);
          if (!matcher_) return sighting;
          answer_ = daemon_->find(name_);
          sighting.claimed = answer_.result == io::FindResult::Seen;
          sighting.reported = answer_.seen_position;
          return sighting;
        },
        matcher_ ? Robot::Recognition::Matcher : Robot::Recognition::Oracle);
  }

  FindmugTables* daemon() const { return daemon_.get(); }
  bool matcher() const { return matcher_; }
  const io::FindResultMessage& answer() const { return answer_; }
  int frames() const { return daemon_ ? daemon_->frames() : 0; }
  // The daemon's frame count and the matcher's counts into `result`.
  void report(EpisodeResult& result) const {
    if (!daemon_) return;
    result.frames_processed = daemon_->frames();
    if (!matcher_) return;
    const auto c = daemon_->objectCounters();
    result.candidates = static_cast<int>(c.candidates);
    result.matches = static_cast<int>(c.matches);
    result.refused_size = static_cast<int>(c.refused_too_big + c.refused_too_small);
    result.refused_colour = static_cast<int>(c.refused_colour);
    result.refused_shape =
        static_cast<int>(c.refused_shape + c.refused_not_round + c.refused_few_points);
  }

 private:
  bool matcher_;
  std::string name_;
  std::unique_ptr<FindmugTables> daemon_;
  // The tables whose tops are watched: the daemon's map, or the known ones.
  const std::vector<TableCluster>& watchedTables() const {
    return daemon_ && known_tables_.empty() ? daemon_->mapTables() : known_tables_;
  }
  void observeTops(const synth::RenderedFrame& frame, const Eigen::Vector2d& xy, double yaw) {
    if (!tops_ || !frame.labeled.frame.extrinsics) return;
    // The robot knows its head's pose: the base pose and the camera mount.
    const Eigen::Isometry3d camera =
        cameraInMap(Pose2D{xy.x(), xy.y(), yaw},
                    groundFromExtrinsics(*frame.labeled.frame.extrinsics).camera_to_ground);
    tops_->observe(watchedTables(), frame.labeled.frame, camera);
  }

  std::unique_ptr<TableTopViews> tops_;
  std::vector<TableCluster> known_tables_;
  io::FindResultMessage answer_;
};

// One place in front of a piece of furniture: the first reachable spot just clear of it,
// trying directions from the one towards its room's centre.
struct Place {
  int cell = -1;
  double yaw = 0.0;
};

// The first reachable spot (from the start) just clear of the piece's footprint, trying
// directions from the one towards its room's centre, facing the piece; nullopt when none.
std::optional<Place> placeBeside(const World& world, const SimParams& params,
                                 const synth::FurnitureTruth& f,
                                 const std::vector<double>& from_start) {
  if (f.room < 0) return std::nullopt;
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& v : f.footprint) c += v / static_cast<double>(f.footprint.size());
  const Eigen::Vector2d to_room = world.apartment.rooms[f.room].center() - c;
  const double a0 = std::atan2(to_room.y(), to_room.x());
  for (int k = 0; k < 16; ++k) {
    const double a = a0 + (k % 2 ? 1 : -1) * ((k + 1) / 2) * (2.0 * M_PI / 16);
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    // Step out until the robot would clear the footprint by 0.15 m.
    double r = 0.0;
    const double clear = params.robot_radius_m + 0.15;
    auto inside = [&](const Eigen::Vector2d& p) {
      const std::size_t n = f.footprint.size();
      for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector2d e = f.footprint[(i + 1) % n] - f.footprint[i];
        const Eigen::Vector2d q = p - f.footprint[i];
        if (e.x() * q.y() - e.y() * q.x() < -clear * e.norm()) return false;
      }
      return true;
    };
    while (r < 3.0 && inside(c + r * dir)) r += 0.05;
    const int cell = reachableCellNear(world.grid, from_start, c + r * dir, 0.1);
    if (cell < 0) continue;
    const Eigen::Vector2d look = c - world.grid.center(cell);
    return Place{cell, std::atan2(look.y(), look.x())};
  }
  return std::nullopt;
}

// Hand-placed: in front of each table, cabinet and shelf (an expert's places). With
// `every_piece`, in front of every footprint of the robot's occupancy grid that stands in a
// room, whatever it is (what a robot knows without semantics: its map's obstacles).
std::vector<Place> placesBesideFurniture(const World& world, const SimParams& params,
                                         bool every_piece) {
  const std::vector<double> from_start = world.grid.distancesFrom(world.grid.cellAt(world.start));
  std::vector<Place> places;
  for (const synth::FurnitureTruth& f : world.apartment.furniture) {
    if (!every_piece && f.kind != "table" && f.kind != "cabinet" && f.kind != "shelf") continue;
    if (const std::optional<Place> place = placeBeside(world, params, f, from_start))
      places.push_back(*place);
  }
  return places;
}

// Visits the places, nearest first by planned path, facing each and looking once.
void visitPlaces(Robot& robot, const World& world, std::vector<Place> todo, int& visited) {
  while (robot.active() && !todo.empty()) {
    const std::vector<double> dist = world.grid.distancesFrom(robot.cell());
    const auto next = std::min_element(
        todo.begin(), todo.end(),
        [&dist](const Place& a, const Place& b) { return dist[a.cell] < dist[b.cell]; });
    const Place place = *next;
    todo.erase(next);
    ++visited;
    robot.driveTo(world.grid.center(place.cell));
    robot.turnTo(place.yaw);
    robot.look();
  }
}

// With the matcher, the findmug strategy also looks this far to either side at a search
// position (half the camera's horizontal field of view).
constexpr double kTopSweepRad = 0.5;

EpisodeResult runFindmug(const World& world, const SimParams& params,
                         const Perception& perception) {
  EpisodeResult result;
  Eyes eyes(perception, true);
  if (params.top_seen_share > 0.0) eyes.watchTops(params);
  FindmugTables& tables = *eyes.daemon();
  Robot robot = eyes.robot(world, params);
  LookCloser closer;
  RoomExplorer rooms(world, params);
  robot.lookAround();
  rooms.lookedAroundHere(robot);
  // One search position per table: its top was in view from there (a table of several
  // positions otherwise has the robot walk round it while other rooms wait).
  std::vector<Eigen::Vector2d> visited;
  std::vector<int> tables_visited;
  // Once every room is explored, the search positions findmugd could not judge come before
  // covering the floor plan (it marks a spot unreachable when its frames did not show the
  // floor there, as behind a table; the robot's occupancy grid decides). Before that they
  // would draw the robot to every sofa taken for a table.
  bool rooms_explored = false;
  while (robot.active()) {
    if (eyes.matcher() && closer.next(robot, eyes.answer(), world)) continue;
    const std::vector<double> dist = world.grid.distancesFrom(robot.cell());
    const MapSearchPosition* next = nullptr;
    int next_cell = -1;
    for (const MapSearchPosition& p : tables.positions()) {
      if (!p.reachable && (params.only_daemon_reachable || !rooms_explored)) continue;
      const bool seen_before =
          std::find(tables_visited.begin(), tables_visited.end(), p.table_id) !=
              tables_visited.end() ||
          (params.top_seen_share > 0.0 && eyes.topSeen(p.table_id) >= params.top_seen_share) ||
          std::any_of(visited.begin(), visited.end(),
                      [&p](const auto& v) { return (v - p.xy).norm() < 0.5; });
      const int c = seen_before ? -1 : reachableCellNear(world.grid, dist, p.xy, 0.25);
      if (c >= 0 && (next_cell < 0 || dist[c] < dist[next_cell])) next = &p, next_cell = c;
    }
    if (next == nullptr) {
      // Exploring a room stops as soon as the map shows a table not known when it began
      // whose top is still to be seen: re-planning as the map grows.
      std::vector<int> known;
      for (const TableCluster& t : tables.mapTables()) known.push_back(t.id);
      const auto new_table = [&] {
        for (const MapSearchPosition& p : tables.positions())
          if (p.reachable && std::find(known.begin(), known.end(), p.table_id) == known.end() &&
              !(params.top_seen_share > 0.0 && eyes.topSeen(p.table_id) >= params.top_seen_share))
            return true;
        return false;
      };
      if (!rooms_explored &&
          rooms.exploreNext(robot, params.replan_on_new_tables ? std::function<bool()>(new_table)
                                                               : std::function<bool()>()))
        continue;
      if (!rooms_explored && !params.only_daemon_reachable) {
        rooms_explored = true;
        robot.note("every room explored: the search positions findmugd could not judge");
        continue;
      }
      robot.note("cover the floor plan");
      coverUntilDone(robot, world, params, false);  // nothing left but the floor plan
      if (params.furniture_after_coverage && robot.active()) {
        // Every room explored, every mapped top seen, the floor plan covered, and the mug
        // not seen: it may stand where only a near view from the right side shows it, on
        // furniture the table map missed or hidden from the views so far. A robot knows
        // where its map's obstacles are: it looks at each from beside it.
        robot.note("look at the furniture of the grid from beside it");
        int beside = 0;
        visitPlaces(robot, world, placesBesideFurniture(world, params, true), beside);
      }
      break;
    }
    const MapSearchPosition target = *next;  // positions() changes with the next frame
    if (params.trace) {
      std::string truth = "?";
      for (const TableCluster& t : tables.mapTables())
        if (t.id == target.table_id) truth = furnitureAt(world, t.center);
      char line[200];
      std::snprintf(line, sizeof line,
                    "search position of table %d (%.2f, %.2f), truth %s, %.0f %% of its top "
                    "seen; %d tables mapped, the mug %.1f m from it",
                    target.table_id, target.xy.x(), target.xy.y(), truth.c_str(),
                    100.0 * eyes.topSeen(target.table_id), tables.tables(),
                    (target.xy - world.mug.position.head<2>()).norm());
      robot.note(line);
    }
    visited.push_back(target.xy);
    tables_visited.push_back(target.table_id);
    ++result.positions_visited;
    // On the way, the top may come into view near enough: then it has been searched.
    const auto top_seen = [&] {
      return params.top_seen_share > 0.0 && eyes.topSeen(target.table_id) >= params.top_seen_share;
    };
    robot.driveTo(world.grid.center(next_cell), params.replan_on_new_tables
                                                    ? std::function<bool()>(top_seen)
                                                    : std::function<bool()>());
    if (robot.interrupted()) continue;  // the top was seen on the way
    robot.turnTo(target.yaw);
    robot.look();
    if (eyes.matcher()) {
      // The matcher needs the mug whole and near the middle of the view, twice: the top
      // to either side of the position's heading as well.
      for (const double side : {kTopSweepRad, -2.0 * kTopSweepRad}) {
        if (!robot.active()) break;
        robot.turnTo(robot.yaw() + side);
        robot.look();
      }
    }
  }
  if (params.trace) {
    // What the map held at the end, and how much of each top the frames showed.
    for (const TableCluster& t : tables.mapTables()) {
      int positions = 0, reachable = 0;
      for (const MapSearchPosition& p : tables.positions())
        if (p.table_id == t.id) ++positions, reachable += p.reachable;
      char line[240];
      std::snprintf(line, sizeof line,
                    "at the end: table %d at (%.2f, %.2f), truth %s, %.0f %% of its top seen, "
                    "%d of %d search positions reachable, the mug %.1f m from its centre",
                    t.id, t.center.x(), t.center.y(), furnitureAt(world, t.center).c_str(),
                    100.0 * eyes.topSeen(t.id), reachable, positions,
                    (t.center.cast<double>() - world.mug.position.head<2>()).norm());
      robot.note(line);
    }
  }
  result.stats = robot.stats();
  result.trace = robot.trace();
  result.tables_mapped = tables.tables();
  eyes.report(result);
  result.look_closer = closer.taken();
  return result;
}

EpisodeResult runPlaces(const World& world, const SimParams& params,
                        const Perception& perception) {
  EpisodeResult result;
  Eyes eyes(perception, false);
  Robot robot = eyes.robot(world, params);
  std::vector<Place> todo = placesBesideFurniture(world, params, false);
  RoomExplorer rooms(world, params);
  visitPlaces(robot, world, std::move(todo), result.positions_visited);
  while (robot.active() && rooms.exploreNext(robot)) {
  }
  coverUntilDone(robot, world, params, false);
  result.stats = robot.stats();
  result.trace = robot.trace();
  eyes.report(result);
  return result;
}

// The apartment's true tables as a perfect table map would hold them: the footprint as the
// top's hull, the top's height, the furniture index as the id.
std::vector<TableCluster> trueTables(const World& world) {
  std::vector<TableCluster> tables;
  for (std::size_t i = 0; i < world.apartment.furniture.size(); ++i) {
    const synth::FurnitureTruth& f = world.apartment.furniture[i];
    if (f.kind != "table") continue;
    TableCluster t;
    t.id = static_cast<int>(i);
    t.top_height = static_cast<float>(f.top_z);
    t.center = f.centre().cast<float>();
    for (const Eigen::Vector2d& v : f.footprint) t.hull.push_back(v.cast<float>());
    tables.push_back(std::move(t));
  }
  return tables;
}

// (f) The findmug strategy's rules on a perfect table map: every true table known from the
// start (so no look-around there), nearest first, skipped once its top was seen near enough;
// then the same fallbacks as (b). Its time over the oracle's is the price of not knowing
// which table holds the mug; findmug's over its own, the price of findmug's table
// perception (missed and false tables, search positions).
EpisodeResult runTables(const World& world, const SimParams& params, const Perception& perception) {
  EpisodeResult result;
  Eyes eyes(perception, false);
  const std::vector<TableCluster> tables = trueTables(world);
  eyes.watchTopsOf(tables, params);
  Robot robot = eyes.robot(world, params);
  struct Target {
    int table_id = -1;
    Place place;
  };
  std::vector<Target> todo;
  const std::vector<double> from_start = world.grid.distancesFrom(robot.cell());
  for (const TableCluster& t : tables)
    if (const std::optional<Place> place =
            placeBeside(world, params, world.apartment.furniture[t.id], from_start))
      todo.push_back({t.id, *place});
  const auto top_seen = [&](int table_id) {
    return params.top_seen_share > 0.0 && eyes.topSeen(table_id) >= params.top_seen_share;
  };
  while (robot.active()) {
    todo.erase(std::remove_if(todo.begin(), todo.end(),
                              [&](const Target& t) { return top_seen(t.table_id); }),
               todo.end());
    if (todo.empty()) break;
    const std::vector<double> dist = world.grid.distancesFrom(robot.cell());
    const auto next = std::min_element(
        todo.begin(), todo.end(),
        [&](const Target& a, const Target& b) { return dist[a.place.cell] < dist[b.place.cell]; });
    const Target target = *next;
    todo.erase(next);
    ++result.positions_visited;
    robot.driveTo(world.grid.center(target.place.cell),
                  [&, id = target.table_id] { return top_seen(id); });
    if (robot.interrupted()) continue;  // the top was seen on the way
    robot.turnTo(target.place.yaw);
    robot.look();
  }
  RoomExplorer rooms(world, params);
  while (robot.active() && rooms.exploreNext(robot)) {
  }
  coverUntilDone(robot, world, params, false);
  result.stats = robot.stats();
  result.trace = robot.trace();
  result.tables_mapped = static_cast<int>(tables.size());
  eyes.report(result);
  return result;
}

// Floor cells seen by the camera: rays across the field of view until a tall obstacle.
class Coverage {
 public:
  Coverage(const World& world, const SimParams& params)
      : world_(world), params_(params), seen_(world.grid.size(), 0), blocks_(world.grid.size(), 0) {
    for (int i = 0; i < world.grid.size(); ++i) {
      const Eigen::Vector2d p = world.grid.center(i);
      for (const synth::Obstacle& o : world.apartment.scene.obstacles) {
        if (o.top_z <= params.camera_height_m - 0.2) continue;  // the camera looks over it
        const std::size_t n = o.polygon.size();
        bool inside = true;
        for (std::size_t k = 0; k < n && inside; ++k) {
          const Eigen::Vector2d e = o.polygon[(k + 1) % n] - o.polygon[k];
          const Eigen::Vector2d q = p - o.polygon[k];
          inside = e.x() * q.y() - e.y() * q.x() >= 0.0;
        }
        if (inside) blocks_[i] = 1;
      }
    }
  }
  void markView(const Eigen::Vector2d& xy, double yaw) {
    for (double a = -0.547; a <= 0.547; a += 0.01) {
      const Eigen::Vector2d dir(std::cos(yaw + a), std::sin(yaw + a));
      for (double r = 0.0; r <= params_.coverage_range_m; r += 0.5 * world_.grid.cell()) {
        const int c = world_.grid.cellAt(xy + r * dir);
        if (c < 0 || blocks_[c]) break;
        seen_[c] = 1;
      }
    }
  }
  // The nearest reachable free cell in a patch of unseen free floor, or -1.
  int nextGoal(const std::vector<double>& dist) const {
    const Grid& g = world_.grid;
    int best = -1;
    for (int i = 0; i < g.size(); ++i) {
      if (seen_[i] || !std::isfinite(dist[i]) || (best >= 0 && dist[i] >= dist[best])) continue;
      int unseen = 0;
      const int cx = i % g.nx(), cy = i / g.nx();
      for (int y = std::max(0, cy - 3); y <= std::min(g.ny() - 1, cy + 3); ++y)
        for (int x = std::max(0, cx - 3); x <= std::min(g.nx() - 1, cx + 3); ++x)
          unseen += g.free(y * g.nx() + x) && !seen_[y * g.nx() + x];
      if (unseen >= 12) best = i;
    }
    return best;
  }

 private:
  const World& world_;
  const SimParams& params_;
  std::vector<std::uint8_t> seen_, blocks_;
};

// Coverage from wherever the robot is: every view taken so far counts as searched floor;
// look around, drive to the nearest floor not yet seen, until none is left.
void coverUntilDone(Robot& robot, const World& world, const SimParams& params, bool look_first) {
  Coverage coverage(world, params);
  std::size_t marked = 0;
  auto mark = [&] {
    for (; marked < robot.viewPoses().size(); ++marked)
      coverage.markView(robot.viewPoses()[marked].first, robot.viewPoses()[marked].second);
  };
  if (look_first) robot.lookAround(false);
  mark();
  while (robot.active()) {
    const int goal = coverage.nextGoal(world.grid.distancesFrom(robot.cell()));
    if (goal < 0 || !robot.driveTo(world.grid.center(goal))) break;
    robot.lookAround(false);
    mark();
  }
}

EpisodeResult runCoverage(const World& world, const SimParams& params,
                          const Perception& perception) {
  EpisodeResult result;
  Eyes eyes(perception, false);
  Robot robot = eyes.robot(world, params);
  coverUntilDone(robot, world, params, true);
  result.stats = robot.stats();
  result.trace = robot.trace();
  eyes.report(result);
  return result;
}

EpisodeResult runRandom(const World& world, const SimParams& params,
                        const Perception& perception) {
  EpisodeResult result;
  Eyes eyes(perception, false);
  Robot robot = eyes.robot(world, params);
  const std::vector<double> dist = world.grid.distancesFrom(robot.cell());
  std::vector<int> reachable;
  for (int i = 0; i < world.grid.size(); ++i)
    if (std::isfinite(dist[i])) reachable.push_back(i);
  std::uint64_t state = mix(world.episode.episode_seed ^ 0x7a4d0ULL);
  robot.lookAround();
  while (robot.active()) {
    state = mix(state);
    robot.driveTo(world.grid.center(reachable[state % reachable.size()]));
    robot.lookAround();
  }
  result.stats = robot.stats();
  result.trace = robot.trace();
  eyes.report(result);
  return result;
}

EpisodeResult runOracle(const World& world, const SimParams& params,
                        const Perception& perception) {
  EpisodeResult result;
  Eyes eyes(perception, false);
  Robot robot = eyes.robot(world, params);
  robot.driveTo(world.best_view);
  robot.turnTo(world.best_view_yaw);
  robot.look();
  if (eyes.matcher()) {
    // The best view is the nearest pose the oracle recognises from, up to 3.5 m away; the
    // object map names an object only after two matches from within object_map's naming
    // range. So: the free pose nearest the mug, facing it, three looks.
    const int near = world.grid.nearestFree(world.mug.position.head<2>(), 1.5);
    if (robot.active() && near >= 0) {
      robot.driveTo(world.grid.center(near));
      const Eigen::Vector2d to = world.mug.position.head<2>() - robot.xy();
      robot.turnTo(std::atan2(to.y(), to.x()));
      for (int k = 0; k < 3 && robot.active(); ++k) robot.look();
    }
  }
  LookCloser closer;
  while (eyes.matcher() && closer.next(robot, eyes.answer(), world)) {
  }
  result.stats = robot.stats();
  result.trace = robot.trace();
  eyes.report(result);
  result.look_closer = closer.taken();
  return result;
}

}  // namespace

std::optional<LookCloser::Choice> LookCloser::choose(const Robot& robot,
                                                     const io::FindResultMessage& answer,
                                                     const World& world) {
  const std::vector<int> tables = FindmugTables::lookCloserTables(answer);
  if (tables.empty()) return std::nullopt;
  const std::vector<double> dist = world.grid.distancesFrom(robot.cell());
  for (const PlaceToLook& place : answer.places) {
    if (std::find(tables.begin(), tables.end(), place.table_id) == tables.end()) continue;
    const Eigen::Vector2d xy = place.position.xy.cast<double>();
    int& visits = visitsNear(xy);
    const int cell = reachableCellNear(world.grid, dist, xy, 0.25);
    if (visits >= 2 || cell < 0) continue;
    ++visits;
    return Choice{place, cell};
  }
  return std::nullopt;
}

bool LookCloser::next(Robot& robot, const io::FindResultMessage& answer, const World& world) {
  if (!robot.active()) return false;
  // A copy: every frame of the drive below replaces `answer` (and frees its places).
  const std::optional<Choice> choice = choose(robot, answer, world);
  if (!choice) return false;
  ++taken_;
  robot.driveTo(world.grid.center(choice->cell));
  robot.turnTo(choice->place.position.yaw);
  robot.look();
  return true;
}

int& LookCloser::visitsNear(const Eigen::Vector2d& xy) {
  for (auto& [at, n] : visits_)
    if ((at - xy).norm() < 0.25) return n;
  visits_.push_back({xy, 0});
  return visits_.back().second;
}

RoomExplorer::RoomExplorer(const World& world, const SimParams& params)
    : world_(world), params_(params), done_(world.apartment.rooms.size()) {
  // Each room's floor plan: its cells that do not block the view (low furniture included:
  // the camera looks over it and would show a mug on it).
  floor_.resize(world.apartment.rooms.size());
  room_of_.assign(world.grid.size(), -1);
  const ViewCoverage blocking(world, params);
  for (int i = 0; i < world.grid.size(); ++i) {
    if (blocking.blocksView(i)) continue;
    const int r = world.apartment.roomAt(world.grid.center(i));
    if (r >= 0) floor_[r].push_back(i), room_of_[i] = r;
  }
}

void RoomExplorer::lookedAroundHere(const Robot& robot) {
  const int r = world_.apartment.roomAt(robot.xy());
  if (r >= 0) done_[r] = true;
}

int RoomExplorer::coveredCells(const Robot& robot, int room) const {
  int seen = 0;
  for (const int c : floor_[room]) seen += robot.viewCoverage().covered(c);
  return seen;
}

double RoomExplorer::seenShare(const Robot& robot, int room) const {
  const std::vector<int>& cells = floor_[room];
  if (cells.empty()) return 1.0;
  return static_cast<double>(coveredCells(robot, room)) / static_cast<double>(cells.size());
}

bool RoomExplorer::explored(const Robot& robot, int room) const {
  return done_[room] || seenShare(robot, room) >= params_.room_seen_share;
}

double RoomExplorer::seenShareAfterLookAround(const Robot& robot, int room,
                                              const Eigen::Vector2d& xy) const {
  const std::vector<int>& cells = floor_[room];
  if (cells.empty()) return 1.0;
  const ViewCoverage& coverage = robot.viewCoverage();
  int seen = coveredCells(robot, room);
  for (const int c : coverage.cellsInViewAround(xy, params_.coverage_range_m))
    seen += room_of_[c] == room && !coverage.covered(c);
  return static_cast<double>(seen) / static_cast<double>(cells.size());
}

bool RoomExplorer::exploreNext(Robot& robot, const std::function<bool()>& stop_when) {
  const std::vector<double> dist = world_.grid.distancesFrom(robot.cell());
  int best_room = -1, best_cell = -1;
  for (std::size_t r = 0; r < done_.size(); ++r) {
    if (explored(robot, static_cast<int>(r))) continue;
    const int c = reachableCellInRoom(world_.grid, dist, world_.apartment.rooms[r]);
    if (c < 0) {
      done_[r] = true;  // nothing of it is reachable
      continue;
    }
    if (best_cell < 0 || dist[c] < dist[best_cell]) best_room = static_cast<int>(r), best_cell = c;
  }
  if (best_cell < 0) return false;
  char line[120];
  std::snprintf(line, sizeof line, "explore room %d (%s), %.0f %% of its floor plan seen",
                best_room, synth::roomKindName(world_.apartment.rooms[best_room].kind),
                100.0 * seenShare(robot, best_room));
  robot.note(line);
  // Whether a look-around where the robot stands would show the room as well as one from
  // the centre, or well enough: then it looks around here.
  const Eigen::Vector2d centre = world_.grid.center(best_cell);
  const auto room_in_view = [&] {
    if (params_.explore_to_room_centres || world_.apartment.roomAt(robot.xy()) != best_room)
      return false;
    const double enough = std::min(params_.room_seen_share,
                                   seenShareAfterLookAround(robot, best_room, centre));
    return seenShareAfterLookAround(robot, best_room, robot.xy()) >= enough;
  };
  bool look_here = room_in_view();
  if (!look_here) {
    const std::function<bool()> stop = [&] {
      if (stop_when && stop_when()) return true;
      look_here = room_in_view();
      return look_here;
    };
    robot.driveTo(centre, stop);
    if (robot.interrupted() && !look_here) return true;
    robot.clearInterrupted();
  }
  done_[best_room] = true;  // also when the drive failed: it is not tried again
  if (look_here) {
    std::snprintf(line, sizeof line,
                  "the room in view: a look-around here shows %.0f %% of its floor plan, at its "
                  "centre %.0f %%",
                  100.0 * seenShareAfterLookAround(robot, best_room, robot.xy()),
                  100.0 * seenShareAfterLookAround(robot, best_room, centre));
    robot.note(line);
  }
  robot.lookAround();
  return true;
}

std::string canonicalStrategy(const std::string& name) {
  static const char* names[] = {"findmug", "places", "coverage", "random", "oracle", "tables"};
  for (int i = 0; i < 6; ++i)
    if (name == names[i] || (name.size() == 1 && name[0] == 'a' + i)) return names[i];
  throw Error("search: unknown strategy '" + name +
              "' (findmug|a, places|b, coverage|c, random|d, oracle|e, tables|f)");
}

EpisodeResult runStrategy(const std::string& strategy, const World& world, const SimParams& params,
                          const Perception& perception) {
  const std::string name = canonicalStrategy(strategy);
  EpisodeResult result;
  if (name == "findmug") {
    result = runFindmug(world, params, perception);
  } else if (name == "places") {
    result = runPlaces(world, params, perception);
  } else if (name == "coverage") {
    result = runCoverage(world, params, perception);
  } else if (name == "random") {
    result = runRandom(world, params, perception);
  } else if (name == "tables") {
    result = runTables(world, params, perception);
  } else {
    result = runOracle(world, params, perception);
  }
  result.strategy = name;
  return result;
}

}  // namespace findmug::search
