// Multi-room apartments for the object-search benchmark (issue 51): rooms of a kind joined by
// doorways, furnished room by room, and a target mug placed by a stated prior.
//
// Why this shape: the renderer's shell is one axis-aligned box (render.cpp casts every ray
// out of it), so the apartment is that box and its interior walls are ordinary box
// primitives, which are also obstacles for every planner. Each room is furnished by the
// single-room generator (makeApartment) in its own frame and moved into place, so the
// existing scenes and their bytes stay exactly as they were.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/synth/synth.hpp"
#include "synth_internal.hpp"

namespace findmug::synth {

using detail::Polygon2;
using detail::Rng;
using detail::at;

namespace {

struct Rect {
  Eigen::Vector2d lo, hi;
  double width() const { return hi.x() - lo.x(); }
  double depth() const { return hi.y() - lo.y(); }
};

// An interior wall on the line x = at (along_y) or y = at, from `from` to `to` along it.
struct WallLine {
  bool along_y = true;
  double at = 0.0, from = 0.0, to = 0.0;
};

// The free interior of a region: interior walls take half their thickness from each side.
Rect interiorOf(const Rect& r, const Eigen::Vector2d& size, double t) {
  Rect in = r;
  if (r.lo.x() > 1e-9) in.lo.x() += t / 2;
  if (r.lo.y() > 1e-9) in.lo.y() += t / 2;
  if (r.hi.x() < size.x() - 1e-9) in.hi.x() -= t / 2;
  if (r.hi.y() < size.y() - 1e-9) in.hi.y() -= t / 2;
  return in;
}

// Guillotine splits of the largest region that can take one until there are `n`; false
// when no region can be split without a room narrower than params.min_room_side.
bool splitRooms(int n, const Eigen::Vector2d& size, const MultiRoomParams& params, Rng& rng,
                std::vector<Rect>& regions, std::vector<WallLine>& walls) {
  regions = {{{0, 0}, size}};
  const double t = params.wall_thickness, m = params.min_room_side;
  while (static_cast<int>(regions.size()) < n) {
    std::vector<std::size_t> order(regions.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return regions[a].width() * regions[a].depth() > regions[b].width() * regions[b].depth();
    });
    const double u = rng.uniform();
    bool split = false;
    for (std::size_t k = 0; k < order.size() && !split; ++k) {
      const Rect r = regions[order[k]];
      const bool wide = r.width() >= r.depth();
      for (int axis_try = 0; axis_try < 2 && !split; ++axis_try) {
        const bool along_y = (axis_try == 0) == wide;  // split across the longer side first
        const double lo = along_y ? r.lo.x() : r.lo.y(), hi = along_y ? r.hi.x() : r.hi.y();
        const double outer = along_y ? size.x() : size.y();
        // Where the wall may go: both rooms keep m of interior (walls take t / 2 a side),
        // and neither gets less than 30 % of the region.
        const double a = std::max(lo + m + t / 2 + (lo > 1e-9 ? t / 2 : 0.0), lo + 0.3 * (hi - lo));
        const double b =
            std::min(hi - m - t / 2 - (hi < outer - 1e-9 ? t / 2 : 0.0), hi - 0.3 * (hi - lo));
        if (a > b) continue;  // (the other side keeps its interior: it is not cut)
        const double c = a + u * (b - a);
        Rect first = r, second = r;
        (along_y ? first.hi.x() : first.hi.y()) = c;
        (along_y ? second.lo.x() : second.lo.y()) = c;
        regions[order[k]] = first;
        regions.push_back(second);
        walls.push_back(along_y ? WallLine{true, c, r.lo.y(), r.hi.y()}
                                : WallLine{false, c, r.lo.x(), r.hi.x()});
        split = true;
      }
    }
    if (!split) return false;
  }
  return true;
}

// Furnishing of one room by its kind: the single-room generator's settings.
ApartmentParams roomParams(RoomKind kind, const Rect& interior, double ceiling) {
  ApartmentParams p;
  p.room_x_min = p.room_x_max = interior.width();
  p.room_y_min = p.room_y_max = interior.depth();
  p.ceiling_min = p.ceiling_max = ceiling;
  p.doors_min = p.doors_max = 0;
  p.windows_min = p.windows_max = 0;
  auto set = [&p](int t0, int t1, int c0, int c1, int s0, int s1) {
    p.tables_min = t0, p.tables_max = t1, p.cabinets_min = c0, p.cabinets_max = c1;
    p.shelves_min = s0, p.shelves_max = s1;
  };
  switch (kind) {
    case RoomKind::Kitchen:
      set(1, 2, 2, 3, 0, 1);
      break;
    case RoomKind::Living:
      set(1, 2, 0, 1, 1, 2);
      break;
    case RoomKind::Bedroom:
      set(1, 1, 1, 2, 0, 1);
      break;
    case RoomKind::Study:
      set(1, 2, 0, 1, 1, 2);
      break;
    case RoomKind::Hall:
      set(1, 1, 1, 2, 0, 1);
      break;
  }
  return p;
}

Primitive boxPart(const Eigen::Vector3d& center, double yaw, const Eigen::Vector3d& half,
                  const Material& m) {
  Primitive p;
  p.center = center;
  p.yaw = yaw;
  p.half_extent = half;
  p.material = m;
  return p;
}

Eigen::Vector2d local(const Eigen::Vector2d& c, double yaw, double lx, double ly) {
  return c + Eigen::Vector2d(std::cos(yaw) * lx - std::sin(yaw) * ly,
                             std::sin(yaw) * lx + std::cos(yaw) * ly);
}

// Moves one furnished room (its objects after the shell) into the apartment at `offset`.
void mergeRoom(MultiRoomApartment& apt, const SynthScene& room, const Eigen::Vector2d& offset,
               int room_index) {
  SynthScene& s = apt.scene;
  const int object_shift = static_cast<int>(s.objects.size()) - 6;
  const int table_shift = static_cast<int>(s.tables.size());
  const Eigen::Vector3d shift3(offset.x(), offset.y(), 0.0);
  for (std::size_t o = 6; o < room.objects.size(); ++o) {
    SceneObject obj = room.objects[o];
    if (obj.table >= 0) obj.table += table_shift;
    s.objects.push_back(obj);
  }
  for (Primitive p : room.primitives) {
    p.center += shift3;
    p.object += object_shift;
    s.primitives.push_back(p);
  }
  for (TableTruth t : room.tables) {
    t.id += table_shift;
    t.object += object_shift;
    t.center_xy += offset;
    for (auto& v : t.top_polygon) v += offset;
    s.tables.push_back(t);
  }
  for (Obstacle o : room.obstacles) {
    o.object += object_shift;
    for (auto& v : o.polygon) v += offset;
    s.obstacles.push_back(o);
    FurnitureTruth f;
    f.object = o.object;
    f.kind = s.objects[o.object].kind;
    f.room = room_index;
    f.table = s.objects[o.object].table;
    f.footprint = o.polygon;
    f.top_z = o.top_z;
    apt.furniture.push_back(f);
  }
}

// A bed or a sofa with its back to a wall of the room; skipped when there is no room.
void addLargeFurniture(MultiRoomApartment& apt, int room_index, bool bed, Rng& rng) {
  const Rect r{apt.rooms[room_index].lo, apt.rooms[room_index].hi};
  const double width = bed ? rng.uniform(1.0, 1.6) : rng.uniform(1.7, 2.2);
  const double depth = bed ? rng.uniform(1.95, 2.1) : rng.uniform(0.8, 0.95);
  for (int attempt = 0; attempt < 80; ++attempt) {
    const int wall = rng.integer(0, 3);
    // Wall origin, direction along it and inward normal (local +y faces the room).
    const Eigen::Vector2d origins[4] = {r.lo, {r.hi.x(), r.lo.y()}, r.lo, {r.lo.x(), r.hi.y()}};
    const Eigen::Vector2d along[4] = {{0, 1}, {0, 1}, {1, 0}, {1, 0}};
    const Eigen::Vector2d inward[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    const double length = wall < 2 ? r.depth() : r.width();
    if (length < width + 0.2) continue;
    const double s = rng.uniform(width / 2 + 0.05, length - width / 2 - 0.05);
    const Eigen::Vector2d c = origins[wall] + s * along[wall] + (depth / 2 + 0.01) * inward[wall];
    const double yaw = std::atan2(-inward[wall].x(), inward[wall].y());
    const Polygon2 footprint = detail::rectangle(c, yaw, width / 2, depth / 2);
    const Polygon2 front =
        detail::rectangle(c + (depth / 2 + 0.4) * inward[wall], yaw, width / 2, 0.4);
    bool free = true;
    for (const auto& o : apt.scene.obstacles)
      free = free && !detail::convexOverlap(footprint, o.polygon) &&
             !detail::convexOverlap(front, o.polygon);
    if (!free) continue;
    std::vector<Primitive> parts;
    const Material frame{{110, 80, 55}, Texture::Wood, 0.03f};
    const Rgb8 fabrics[] = {{70, 90, 130}, {150, 60, 55}, {120, 120, 110}, {60, 110, 80}};
    const Material fabric{fabrics[rng.integer(0, 3)], Texture::Carpet, 0.01f};
    double top = 0.0;
    if (bed) {
      top = rng.uniform(0.5, 0.6);
      parts.push_back(boxPart(at(c, 0.15), yaw, {width / 2, depth / 2, 0.15}, frame));
      parts.push_back(boxPart(at(c, 0.3 + (top - 0.3) / 2), yaw,
                              {width / 2 - 0.02, depth / 2 - 0.02, (top - 0.3) / 2},
                              Material{{235, 235, 240}, Texture::Plain, 0.2f}));
      parts.push_back(boxPart(at(local(c, yaw, 0.0, -depth / 2 + 0.03), 0.5), yaw,
                              {width / 2, 0.03, 0.5}, frame));  // headboard
    } else {
      top = 0.45;
      parts.push_back(boxPart(at(c, 0.225), yaw, {width / 2, depth / 2, 0.225}, fabric));
      parts.push_back(boxPart(at(local(c, yaw, 0.0, -depth / 2 + 0.1), 0.6), yaw,
                              {width / 2, 0.1, 0.25}, fabric));  // back
      for (int sx : {-1, 1})
        parts.push_back(boxPart(at(local(c, yaw, sx * (width / 2 - 0.1), 0.0), 0.3), yaw,
                                {0.1, depth / 2, 0.3}, fabric));  // arm rests
    }
    const int object = addObject(apt.scene, bed ? "bed" : "sofa", Label::Unknown, std::move(parts));
    apt.scene.obstacles.push_back({footprint, bed ? 1.0 : 0.85, object});
    apt.furniture.push_back({object, bed ? "bed" : "sofa", room_index, -1, footprint, top});
    return;
  }
}

// A doorway centre along `w` (free of T-junctions and of furniture on both sides), or NaN.
double doorwayPosition(const WallLine& w, const std::vector<WallLine>& walls,
                       const MultiRoomApartment& apt, const MultiRoomParams& params, Rng& rng) {
  const double half = params.door_width / 2;
  std::vector<double> junctions;
  for (const WallLine& o : walls) {
    if (o.along_y == w.along_y) continue;
    for (double end : {o.from, o.to})
      if (std::abs(end - w.at) < 1e-6 && o.at > w.from && o.at < w.to) junctions.push_back(o.at);
  }
  std::vector<double> candidates;
  for (double s = w.from + half + 0.3; s <= w.to - half - 0.3; s += 0.05) {
    bool ok = true;
    for (double j : junctions) ok = ok && std::abs(s - j) > half + 0.25;
    const Eigen::Vector2d c = w.along_y ? Eigen::Vector2d(w.at, s) : Eigen::Vector2d(s, w.at);
    const Polygon2 corridor = w.along_y ? detail::rectangle(c, 0.0, 0.8, half + 0.05)
                                        : detail::rectangle(c, 0.0, half + 0.05, 0.8);
    for (const auto& o : apt.scene.obstacles)
      ok = ok && !detail::convexOverlap(corridor, o.polygon);
    if (ok) candidates.push_back(s);
  }
  if (candidates.empty()) return std::nan("");
  return candidates[rng.integer(0, static_cast<int>(candidates.size()) - 1)];
}

// One wall piece from a to b along the wall line: a primitive and an obstacle.
void addWallPiece(MultiRoomApartment& apt, const WallLine& w, double a, double b,
                  const MultiRoomParams& params) {
  if (b - a < 1e-3) return;
  const double mid = 0.5 * (a + b), t = params.wall_thickness, h = params.ceiling;
  const Eigen::Vector2d c = w.along_y ? Eigen::Vector2d(w.at, mid) : Eigen::Vector2d(mid, w.at);
  const Eigen::Vector3d half = w.along_y ? Eigen::Vector3d(t / 2, (b - a) / 2, h / 2)
                                         : Eigen::Vector3d((b - a) / 2, t / 2, h / 2);
  const int object = addObject(apt.scene, "wall", Label::Wall,
                               {boxPart(at(c, h / 2), 0.0, half, apt.scene.wall_material)});
  apt.scene.obstacles.push_back({detail::rectangle(c, 0.0, half.x(), half.y()), h, object});
}

// True when one free-space region of the planning grid reaches into every room.
bool roomsConnected(const MultiRoomApartment& apt) {
  const detail::PlanningGrid grid(apt.scene, 0.3);
  std::vector<int> common;  // regions found in every room so far
  for (std::size_t i = 0; i < apt.rooms.size(); ++i) {
    const RoomTruth& r = apt.rooms[i];
    std::vector<int> here;
    for (double x = r.lo.x() + 0.3; x < r.hi.x() - 0.3; x += 0.1)
      for (double y = r.lo.y() + 0.3; y < r.hi.y() - 0.3; y += 0.1) {
        const int c = grid.componentAt({x, y});
        if (c >= 0 && std::find(here.begin(), here.end(), c) == here.end()) here.push_back(c);
      }
    if (i == 0) {
      common = here;
    } else {
      std::erase_if(
          common, [&here](int c) { return std::find(here.begin(), here.end(), c) == here.end(); });
    }
  }
  return !common.empty();
}

bool tryMultiRoom(std::uint64_t seed, int attempt, const MultiRoomParams& params,
                  MultiRoomApartment& apt) {
  Rng rng(detail::hash3(seed, static_cast<std::uint64_t>(attempt), 0x3a9a47ULL));
  const int n = rng.integer(params.rooms_min, params.rooms_max);
  const double area = n * rng.uniform(params.room_area_min, params.room_area_max);
  const double aspect = rng.uniform(1.0, 1.7);
  const Eigen::Vector2d size(std::sqrt(area * aspect), std::sqrt(area / aspect));
  std::vector<Rect> regions;
  std::vector<WallLine> walls;
  if (!splitRooms(n, size, params, rng, regions, walls)) return false;

  apt = {};
  apt.scene = makeEmptyRoom({size.x(), size.y(), params.ceiling});
  apt.scene.seed = seed;
  apt.scene.wall_material = {{232, 230, 222}, Texture::Plain, 0.2f};
  apt.scene.floor_material = {{175, 135, 95}, Texture::Planks, 0.15f};
  // Kinds: the hall is the smallest room, the others shuffled.
  const RoomKind kinds[] = {RoomKind::Living, RoomKind::Kitchen, RoomKind::Bedroom,
                            RoomKind::Study,  RoomKind::Hall,    RoomKind::Bedroom};
  std::vector<RoomKind> assigned(kinds, kinds + n);
  for (int i = n - 1; i > 0; --i) std::swap(assigned[i], assigned[rng.integer(0, i)]);
  const auto hall = std::find(assigned.begin(), assigned.end(), RoomKind::Hall);
  if (hall != assigned.end()) {
    std::size_t smallest = 0;
    for (std::size_t i = 1; i < regions.size(); ++i)
      if (regions[i].width() * regions[i].depth() <
          regions[smallest].width() * regions[smallest].depth())
        smallest = i;
    std::swap(*hall, assigned[smallest]);
  }
  for (int i = 0; i < n; ++i) {
    const Rect in = interiorOf(regions[i], size, params.wall_thickness);
    apt.rooms.push_back({assigned[i], in.lo, in.hi});
    SynthScene room;
    try {
      room = makeApartment(detail::hash3(seed, static_cast<std::uint64_t>(attempt), 100 + i),
                           roomParams(assigned[i], in, params.ceiling));
    } catch (const Error&) {
      return false;  // the room could not hold its furniture; try another layout
    }
    mergeRoom(apt, room, in.lo, i);
    if (assigned[i] == RoomKind::Bedroom || assigned[i] == RoomKind::Living)
      addLargeFurniture(apt, i, assigned[i] == RoomKind::Bedroom, rng);
  }
  for (const WallLine& w : walls) {
    const double s = doorwayPosition(w, walls, apt, params, rng);
    if (std::isnan(s)) return false;
    addWallPiece(apt, w, w.from, s - params.door_width / 2, params);
    addWallPiece(apt, w, s + params.door_width / 2, w.to, params);
    apt.doorways.push_back({w.along_y ? Eigen::Vector2d(w.at, s) : Eigen::Vector2d(s, w.at),
                            w.along_y, params.door_width});
  }
  return roomsConnected(apt);
}

void validate(const MultiRoomParams& p) {
  auto bad = [](const std::string& what) { throw Error("synth: multi-room apartment: " + what); };
  if (!(p.rooms_min >= 1 && p.rooms_min <= p.rooms_max && p.rooms_max <= 8))
    bad("rooms range must be within 1..8");
  if (!(p.room_area_min >= 10.0 && p.room_area_min <= p.room_area_max && p.room_area_max <= 60.0))
    bad("room_area range must be within 10..60 m^2");
  if (!(p.min_room_side >= 3.0 && p.min_room_side <= 8.0)) bad("min_room_side must be 3..8 m");
  if (!(p.wall_thickness >= 0.05 && p.wall_thickness <= 0.3)) bad("wall_thickness 0.05..0.3 m");
  if (!(p.door_width >= 0.8 && p.door_width <= 2.0)) bad("door_width must be 0.8..2 m");
  if (!(p.ceiling >= 2.2 && p.ceiling <= 4.0)) bad("ceiling must be 2.2..4 m");
}

// A mug footprint at `c` on a surface at height z is free of the small objects there.
bool clearOfSmallObjects(const SynthScene& scene, const Eigen::Vector2d& c, double z) {
  for (const Primitive& p : scene.primitives) {
    if (scene.objects[p.object].label != Label::Object) continue;
    if (p.center.z() - p.half_extent.z() > z + 0.15 || p.center.z() + p.half_extent.z() < z - 0.02)
      continue;
    const double r = std::hypot(p.half_extent.x(), p.half_extent.y());
    if ((p.center.head<2>() - c).norm() < r + 0.07) return false;
  }
  return true;
}

struct MugSurface {
  Polygon2 outline;  // where the mug's centre may stand
  double z = 0.0;
  int furniture = -1;
};

std::vector<MugSurface> surfacesFor(const MultiRoomApartment& apt, MugPlace place) {
  std::vector<MugSurface> out;
  const SynthScene& s = apt.scene;
  for (std::size_t f = 0; f < apt.furniture.size(); ++f) {
    const FurnitureTruth& ft = apt.furniture[f];
    if (place == MugPlace::Table && ft.table >= 0) {
      const TableTruth& t = s.tables[ft.table];
      const Polygon2 top =
          t.shape == TableShape::Round
              ? detail::circle(t.center_xy, t.size.x() / 2 - 0.08, 32)
              : detail::rectangle(t.center_xy, t.yaw, t.size.x() / 2 - 0.08, t.size.y() / 2 - 0.08);
      out.push_back({top, t.height, static_cast<int>(f)});
    } else if (place == MugPlace::Cabinet && ft.kind == "cabinet" && ft.top_z <= 1.2) {
      // The footprint is the top; shrink it towards its centre.
      Eigen::Vector2d c = Eigen::Vector2d::Zero();
      for (const auto& v : ft.footprint) c += v / static_cast<double>(ft.footprint.size());
      Polygon2 top;
      for (const auto& v : ft.footprint) top.push_back(c + 0.7 * (v - c));
      out.push_back({top, ft.top_z, static_cast<int>(f)});
    } else if (place == MugPlace::Cabinet && ft.kind == "shelf") {
      for (const Primitive& p : s.primitives) {  // boards: thin horizontal boxes
        if (p.object != ft.object || p.half_extent.z() > 0.015) continue;
        const double z = p.center.z() + p.half_extent.z();
        if (z < 0.25 || z > 1.5) continue;
        out.push_back({detail::rectangle(p.center.head<2>(), p.yaw, p.half_extent.x() - 0.07,
                                         std::max(0.01, p.half_extent.y() - 0.07)),
                       z, static_cast<int>(f)});
      }
    }
  }
  return out;
}

// A random point of a convex polygon's bounding box inside it (rejection sampling).
bool samplePolygon(const Polygon2& poly, Rng& rng, Eigen::Vector2d& out) {
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const auto& v : poly) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  for (int k = 0; k < 20; ++k) {
    const double x = rng.uniform(lo.x(), hi.x());
    const double y = rng.uniform(lo.y(), hi.y());
    if (detail::insideConvex(poly, {x, y})) {
      out = {x, y};
      return true;
    }
  }
  return false;
}

// A floor spot: inside a room, clear of furniture and doorways.
bool sampleFloor(const MultiRoomApartment& apt, Rng& rng, Eigen::Vector2d& out, int& room) {
  room = rng.integer(0, static_cast<int>(apt.rooms.size()) - 1);
  const RoomTruth& r = apt.rooms[room];
  const Eigen::Vector2d p(rng.uniform(r.lo.x() + 0.1, r.hi.x() - 0.1),
                          rng.uniform(r.lo.y() + 0.1, r.hi.y() - 0.1));
  for (const auto& o : apt.scene.obstacles)
    if (detail::insideConvex(o.polygon, p, 0.1)) return false;
  for (const auto& d : apt.doorways)
    if ((d.center - p).norm() < 1.2) return false;
  out = p;
  return true;
}

}  // namespace

const char* roomKindName(RoomKind kind) {
  switch (kind) {
    case RoomKind::Kitchen:
      return "kitchen";
    case RoomKind::Living:
      return "living";
    case RoomKind::Bedroom:
      return "bedroom";
    case RoomKind::Study:
      return "study";
    case RoomKind::Hall:
      return "hall";
  }
  return "?";
}

const char* mugPlaceName(MugPlace place) {
  switch (place) {
    case MugPlace::Table:
      return "table";
    case MugPlace::Cabinet:
      return "cabinet";
    case MugPlace::Floor:
      return "floor";
  }
  return "?";
}

int MultiRoomApartment::roomAt(const Eigen::Vector2d& xy) const {
  for (std::size_t i = 0; i < rooms.size(); ++i)
    if (rooms[i].contains(xy)) return static_cast<int>(i);
  return -1;
}

MultiRoomApartment makeMultiRoomApartment(std::uint64_t seed, const MultiRoomParams& params) {
  validate(params);
  MultiRoomApartment apt;
  for (int attempt = 0; attempt < 40; ++attempt)
    if (tryMultiRoom(seed, attempt, params, apt)) return apt;
  throw Error("synth: no connected multi-room apartment for seed " + std::to_string(seed) +
              " after 40 attempts");
}

Eigen::Vector2d FurnitureTruth::centre() const {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& corner : footprint) sum += corner;
  return sum / static_cast<double>(std::max<std::size_t>(1, footprint.size()));
}

bool FurnitureTruth::covers(const Eigen::Vector2d& xy) const {
  if (footprint.size() < 3) return false;
  for (std::size_t i = 0; i < footprint.size(); ++i) {
    const Eigen::Vector2d edge = footprint[(i + 1) % footprint.size()] - footprint[i];
    const Eigen::Vector2d to = xy - footprint[i];
    if (edge.x() * to.y() - edge.y() * to.x() < 0.0) return false;  // right of a CCW edge
  }
  return true;
}

std::vector<CameraPose> apartmentViews(const MultiRoomApartment& apt, int n_views,
                                       std::uint64_t seed, const CameraPathParams& params) {
  validate(params);
  if (n_views < 0)
    throw Error("synth: apartmentViews: n_views = " + std::to_string(n_views) + " < 0");
  if (apt.furniture.empty())
    throw Error("synth: apartmentViews: the apartment has no furniture");
  Rng rng(detail::hash3(seed, 0x71e75, 0));
  // Every piece in turn, in an order of the seed's: beds and sofas as often as tables.
  std::vector<int> order(apt.furniture.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  for (std::size_t i = order.size(); i > 1; --i) {
    const int pick = rng.integer(0, static_cast<int>(i) - 1);
    std::swap(order[i - 1], order[static_cast<std::size_t>(pick)]);
  }
  std::vector<CameraPose> views;
  for (std::size_t k = 0; static_cast<int>(views.size()) < n_views; ++k) {
    if (k >= order.size() * 4 && views.empty())
      throw Error("synth: apartmentViews: no spot in seed " + std::to_string(seed) +
                  "'s apartment where the robot fits and sees its furniture");
    const FurnitureTruth& piece = apt.furniture[order[k % order.size()]];
    const Eigen::Vector2d centre = piece.centre();
    for (int attempt = 0; attempt < 60; ++attempt) {
      const double distance = rng.uniform(0.9, params.max_view_distance_m + 0.8);
      const double bearing = rng.uniform(-M_PI, M_PI);
      const Eigen::Vector2d stand =
          centre + distance * Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
      if (apt.roomAt(stand) != piece.room ||
          !robotFits(apt.scene.room_size, apt.scene.obstacles, stand, params.robot_radius_m))
        continue;
      CameraPose pose;
      pose.xy = stand;
      const Eigen::Vector2d to = centre - stand;
      pose.yaw = std::atan2(to.y(), to.x()) + rng.uniform(-params.pan_amplitude_rad * 2.0,
                                                          params.pan_amplitude_rad * 2.0);
      pose.height_m = rng.uniform(params.height_min, params.height_max);
      pose.pitch_rad = rng.uniform(params.pitch_min_deg, params.pitch_max_deg) * M_PI / 180.0;
      pose.time_s = static_cast<double>(views.size());
      views.push_back(pose);
      break;
    }
  }
  return views;
}

bool looksLikeTargetMugRed(Rgb8 colour) {
  // The palette's red is 5:1 red to green and blue, its orange 2:1; the jitter moves the
  // ratio by at most 13 %, so 3:1 parts them with room on both sides.
  return colour.r >= 100 && colour.r >= 3 * std::max(colour.g, colour.b);
}

namespace {

// Every small object of kind "mug" as red as the target gets the blue of its brightness
// (channels rotated): one mug in the apartment looks like the target. Returns how many.
int recolourLookAlikeMugs(SynthScene& scene) {
  std::vector<bool> recoloured(scene.objects.size(), false);
  for (const Primitive& p : scene.primitives)
    if (scene.objects[p.object].kind == "mug" && looksLikeTargetMugRed(p.material.color))
      recoloured[p.object] = true;
  for (Primitive& p : scene.primitives) {
    if (!recoloured[p.object]) continue;
    const Rgb8 c = p.material.color;
    p.material.color = {c.g, c.b, c.r};
  }
  return static_cast<int>(std::count(recoloured.begin(), recoloured.end(), true));
}

}  // namespace

TargetMug placeTargetMug(MultiRoomApartment& apt, std::uint64_t seed, const MugPrior& prior,
                         LookAlikes look_alikes) {
  const double total = prior.table + prior.cabinet + prior.floor;
  if (!(prior.table >= 0 && prior.cabinet >= 0 && prior.floor >= 0 && total > 0 &&
        std::isfinite(total)))
    throw Error("synth: mug prior must be non-negative with a positive sum");
  Rng rng(detail::hash3(seed, 0x6d7567ULL, 1));
  const double u = rng.uniform() * total;
  TargetMug mug;
  mug.place = u < prior.table                   ? MugPlace::Table
              : u < prior.table + prior.cabinet ? MugPlace::Cabinet
                                                : MugPlace::Floor;
  const double r = rng.uniform(0.038, 0.045);
  mug.height = rng.uniform(0.09, 0.11);
  std::vector<MugSurface> surfaces;
  if (mug.place != MugPlace::Floor) {
    surfaces = surfacesFor(apt, mug.place);
    if (surfaces.empty()) mug.place = MugPlace::Floor;  // e.g. no low cabinet: the floor
  }
  bool placed = false;
  for (int attempt = 0; attempt < 400 && !placed; ++attempt) {
    Eigen::Vector2d c;
    double z = 0.0;
    if (mug.place == MugPlace::Floor) {
      if (!sampleFloor(apt, rng, c, mug.room)) continue;
    } else {
      const MugSurface& s = surfaces[rng.integer(0, static_cast<int>(surfaces.size()) - 1)];
      if (!samplePolygon(s.outline, rng, c)) continue;
      z = s.z;
      mug.furniture = s.furniture;
      mug.room = apt.furniture[s.furniture].room;
    }
    if (!clearOfSmallObjects(apt.scene, c, z)) continue;
    mug.position = {c.x(), c.y(), z};
    placed = true;
  }
  if (!placed)
    throw Error("synth: no free place for the target mug (seed " + std::to_string(seed) + ")");
  const Material red{{205, 35, 35}, Texture::Plain, 0.2f};
  const double handle_yaw = rng.uniform(0.0, 2.0 * M_PI);
  const Eigen::Vector2d c = mug.position.head<2>();
  Primitive body;
  body.shape = Shape::Cylinder;
  body.center = at(c, mug.position.z() + mug.height / 2);
  body.half_extent = {r, r, mug.height / 2};
  body.material = red;
  const Primitive handle =
      boxPart(at(local(c, handle_yaw, r + 0.012, 0.0), mug.position.z() + mug.height * 0.55),
              handle_yaw, {0.014, 0.006, mug.height * 0.28}, red);
  if (look_alikes == LookAlikes::Recolour)
    mug.look_alikes_recoloured = recolourLookAlikeMugs(apt.scene);
  mug.object = addObject(apt.scene, "target_mug", Label::Object, {body, handle});
  if (mug.place == MugPlace::Floor)
    apt.scene.obstacles.push_back({detail::circle(c, r + 0.03, 8), mug.height, mug.object});
  return mug;
}

}  // namespace findmug::synth
