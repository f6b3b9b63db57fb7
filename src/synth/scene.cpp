// Procedural apartment rooms: shell, doors/windows, tables, chairs, cabinets,
// shelves and small objects, all drawn from one deterministic RNG stream.
#include <algorithm>
#include <array>
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

std::uint8_t clampByte(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
}

// Per-object colour variation: overall brightness and a little per channel.
Rgb8 jitter(Rgb8 c, double amount, Rng& rng) {
  const double gain = 1.0 + amount * rng.uniform(-1.0, 1.0);
  auto ch = [&](std::uint8_t v) {
    return clampByte(v * gain * (1.0 + 0.4 * amount * rng.uniform(-1.0, 1.0)));
  };
  return {ch(c.r), ch(c.g), ch(c.b)};
}

template <typename T, std::size_t N>
const T& pick(const T (&options)[N], Rng& rng) {
  return options[rng.integer(0, static_cast<int>(N) - 1)];
}

// Uniform draws per component, the last component first. Drawn inside one call's arguments
// they would come in an unspecified order (g++ evaluates right to left, clang left to right),
// and a seed would render another scene with another compiler; this fixes the order g++ used,
// so every seed keeps the scene it always had.
Eigen::Vector2d uniform2(Rng& rng, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const double y = rng.uniform(lo.y(), hi.y());
  const double x = rng.uniform(lo.x(), hi.x());
  return {x, y};
}

Eigen::Vector3d uniform3(Rng& rng, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const double z = rng.uniform(lo.z(), hi.z());
  const double y = rng.uniform(lo.y(), hi.y());
  const double x = rng.uniform(lo.x(), hi.x());
  return {x, y, z};
}

Primitive box(const Eigen::Vector3d& center, double yaw, const Eigen::Vector3d& half,
              const Material& material) {
  Primitive p;
  p.shape = Shape::Box;
  p.center = center;
  p.yaw = yaw;
  p.half_extent = half;
  p.material = material;
  return p;
}

Primitive cylinder(const Eigen::Vector3d& center, double radius, double half_height,
                   const Material& material) {
  Primitive p;
  p.shape = Shape::Cylinder;
  p.center = center;
  p.half_extent = Eigen::Vector3d(radius, radius, half_height);
  p.material = material;
  return p;
}

// Local (x, y) of a yawed frame to world xy.
Eigen::Vector2d toWorld(const Eigen::Vector2d& center, double yaw, double lx, double ly) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return center + Eigen::Vector2d(c * lx - s * ly, s * lx + c * ly);
}

// The four walls as lines: a point at distance `s` along wall w, `offset`
// metres into the room, and the yaw whose local +y faces into the room.
struct Wall {
  Eigen::Vector2d origin, along, inward;
  double length;
  double yaw() const { return std::atan2(-inward.x(), inward.y()); }
  Eigen::Vector2d point(double s, double offset) const {
    return origin + s * along + offset * inward;
  }
};

std::array<Wall, 4> wallsOf(const Eigen::Vector3d& room) {
  const double X = room.x(), Y = room.y();
  return {{{{0, 0}, {0, 1}, {1, 0}, Y},
           {{X, 0}, {0, 1}, {-1, 0}, Y},
           {{0, 0}, {1, 0}, {0, 1}, X},
           {{0, Y}, {1, 0}, {0, -1}, X}}};
}

void checkRange(const char* name, double lo, double hi, double min_allowed, double max_allowed) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi || lo < min_allowed || hi > max_allowed) {
    std::ostringstream msg;
    msg << "synth: " << name << " range [" << lo << ", " << hi << "] is empty or outside ["
        << min_allowed << ", " << max_allowed << "]";
    throw Error(msg.str());
  }
}

// Everything placed so far that later furniture must not overlap.
struct Layout {
  Eigen::Vector3d room;
  std::vector<std::pair<Polygon2, int>> solids;  // footprint, object index
  std::vector<Polygon2> keepouts;                // door swing areas

  bool insideRoom(const Polygon2& poly, double margin) const {
    for (const auto& v : poly)
      if (v.x() < margin || v.y() < margin || v.x() > room.x() - margin ||
          v.y() > room.y() - margin)
        return false;
    return true;
  }
  bool free(const Polygon2& poly, int ignore_object = -1) const {
    for (const auto& [solid, object] : solids)
      if (object != ignore_object && detail::convexOverlap(poly, solid)) return false;
    for (const auto& k : keepouts)
      if (detail::convexOverlap(poly, k)) return false;
    return true;
  }
};

// Items resting on one horizontal surface (a table top, a shelf board).
struct Surface {
  Polygon2 outline;  // where an item's footprint must stay inside
  double z = 0.0;
  double max_height = 1.0;
  std::vector<Polygon2> taken;
};

const Rgb8 kObjectColors[] = {{200, 40, 40},   {40, 90, 200}, {240, 240, 235}, {30, 30, 35},
                              {230, 190, 40},  {60, 150, 70}, {220, 110, 30},  {120, 60, 150},
                              {170, 170, 175}, {90, 60, 40}};

// Tries to put one small object (mug, box or book) on `surface`.
void placeSmallObject(SynthScene& scene, Surface& surface, Rng& rng, bool upright_books) {
  // Bounding box of the outline, for sampling.
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const auto& v : surface.outline) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double kind = rng.uniform();
  for (int attempt = 0; attempt < 30; ++attempt) {
    const Eigen::Vector2d c = uniform2(rng, lo, hi);
    std::vector<Primitive> parts;
    Polygon2 footprint;
    std::string name;
    Material m{jitter(pick(kObjectColors, rng), 0.15, rng), Texture::Plain, 0.2f};
    if (kind < 0.4) {  // mug with a handle
      const double r = rng.uniform(0.037, 0.045), h = rng.uniform(0.085, 0.11);
      if (h > surface.max_height) return;
      const double handle_yaw = rng.uniform(0.0, 2.0 * M_PI);
      footprint = detail::circle(c, r + 0.03, 8);
      parts.push_back(cylinder(at(c, surface.z + h / 2), r, h / 2, m));
      parts.push_back(box(at(toWorld(c, handle_yaw, r + 0.012, 0.0), surface.z + h * 0.55),
                          handle_yaw, {0.014, 0.006, h * 0.28}, m));
      name = "mug";
    } else if (kind < 0.7 || upright_books) {
      const bool book = kind >= 0.7;
      const Eigen::Vector3d half =
          book ? uniform3(rng, {0.01, 0.07, 0.08}, {0.025, 0.11, 0.13})
               : uniform3(rng, {0.04, 0.04, 0.03}, {0.12, 0.10, 0.10});
      if (2 * half.z() > surface.max_height) continue;
      const double yaw = upright_books ? 0.0 : rng.uniform(0.0, M_PI);
      footprint = detail::rectangle(c, yaw, half.x(), half.y());
      parts.push_back(box(at(c, surface.z + half.z()), yaw, half, m));
      name = book ? "book" : "box";
    } else {  // a small stack of books lying flat
      const int n = rng.integer(1, 3);
      const double base_yaw = rng.uniform(0.0, M_PI);
      double z = surface.z;
      double max_half_x = 0, max_half_y = 0;
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d half = uniform3(rng, {0.07, 0.05, 0.01}, {0.12, 0.085, 0.025});
        Material bm{jitter(pick(kObjectColors, rng), 0.15, rng), Texture::Plain, 0.2f};
        parts.push_back(box(at(c, z + half.z()), base_yaw + rng.uniform(-0.15, 0.15), half, bm));
        z += 2 * half.z();
        max_half_x = std::max(max_half_x, half.x());
        max_half_y = std::max(max_half_y, half.y());
      }
      if (z - surface.z > surface.max_height) return;
      // Generous footprint: covers the yaw jitter of the stack.
      const double rr = std::hypot(max_half_x, max_half_y);
      footprint = detail::circle(c, rr, 8);
      name = "book";
    }
    bool ok = true;
    for (const auto& v : footprint) ok = ok && detail::insideConvex(surface.outline, v);
    for (const auto& t : surface.taken) ok = ok && !detail::convexOverlap(footprint, t);
    if (!ok) continue;
    surface.taken.push_back(footprint);
    addObject(scene, name, Label::Object, std::move(parts));
    return;
  }
}

Material woodMaterial(Rng& rng) {
  const Rgb8 woods[] = {
      {150, 105, 65}, {120, 80, 50}, {185, 145, 100}, {95, 60, 40}, {200, 170, 125}};
  return {jitter(pick(woods, rng), 0.12, rng), Texture::Wood,
          static_cast<float>(rng.uniform(0.02, 0.05))};
}

Material laminateMaterial(Rng& rng) {
  const Rgb8 colors[] = {{235, 235, 230}, {60, 60, 62}, {200, 200, 195}, {170, 190, 200}};
  return {jitter(pick(colors, rng), 0.08, rng), Texture::Plain, 0.2f};
}

struct TableKind {
  const char* name;
  double weight, h_lo, h_hi, p_round;
  double l_lo, l_hi, w_lo, w_hi, d_lo, d_hi;  // rect length/width, round diameter
  int chairs_lo, chairs_hi;
  bool against_wall;
};

const TableKind kTableKinds[] = {
    {"dining", 0.40, 0.72, 0.78, 0.30, 1.2, 1.8, 0.75, 1.0, 0.9, 1.2, 2, 6, false},
    {"desk", 0.25, 0.70, 0.78, 0.00, 1.0, 1.6, 0.60, 0.8, 0.0, 0.0, 1, 1, true},
    {"coffee", 0.20, 0.45, 0.50, 0.35, 0.8, 1.2, 0.50, 0.7, 0.6, 0.9, 0, 0, false},
    {"bar", 0.15, 1.00, 1.10, 0.50, 0.8, 1.2, 0.50, 0.7, 0.6, 0.8, 0, 2, false},
};

void addChair(SynthScene& scene, Layout& layout, const Eigen::Vector2d& center, double yaw,
              bool stool, int table_object, Rng& rng) {
  const double sw = rng.uniform(0.2, 0.24), sd = rng.uniform(0.2, 0.23);
  const double sh = stool ? rng.uniform(0.62, 0.72) : rng.uniform(0.43, 0.48);
  const Polygon2 footprint = detail::rectangle(center, yaw, sw, sd);
  if (!layout.insideRoom(footprint, 0.02) || !layout.free(footprint, table_object)) return;
  const Rgb8 colors[] = {
      {110, 75, 45}, {40, 40, 45}, {200, 60, 50}, {225, 225, 220}, {70, 110, 160}};
  const bool wooden = rng.chance(0.5);
  const Material m = wooden ? woodMaterial(rng)
                            : Material{jitter(pick(colors, rng), 0.1, rng), Texture::Plain, 0.2f};
  const Material legs = rng.chance(0.5) ? m : Material{{150, 150, 155}, Texture::Plain, 0.2f};
  std::vector<Primitive> parts;
  const double seat_th = 0.04;
  parts.push_back(box(at(center, sh - seat_th / 2), yaw, {sw, sd, seat_th / 2}, m));
  const double leg = 0.017, leg_h = sh - seat_th;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      parts.push_back(
          box(at(toWorld(center, yaw, sx * (sw - leg - 0.01), sy * (sd - leg - 0.01)), leg_h / 2),
              yaw, {leg, leg, leg_h / 2}, legs));
  if (!stool) {  // backrest on the side away from the table (local -y)
    const double bh = rng.uniform(0.35, 0.5);
    parts.push_back(box(at(toWorld(center, yaw, 0.0, -(sd - 0.015)), sh + bh / 2), yaw,
                        {sw, 0.015, bh / 2}, m));
  }
  const int object = addObject(scene, "chair", Label::Chair, std::move(parts));
  layout.solids.push_back({footprint, object});
  scene.obstacles.push_back({footprint, sh + 0.5, object});
}

// Chairs around a table: seat centres just beyond the edges, facing the table.
void addChairs(SynthScene& scene, Layout& layout, const TableTruth& t, const TableKind& kind,
               Rng& rng) {
  const int n = rng.integer(kind.chairs_lo, kind.chairs_hi);
  if (n == 0) return;
  struct Slot {
    double lx, ly;  // chair centre in table coordinates
  };
  std::vector<Slot> slots;
  const double gap = 0.08;  // the chair centre sits this far outside the edge plus a random pull
  if (t.shape == TableShape::Round) {
    const double r = t.size.x() / 2 + gap + 0.1;
    const double a0 = rng.uniform(0.0, 2.0 * M_PI);
    for (int k = 0; k < n; ++k) {
      const double a = a0 + 2.0 * M_PI * k / n;
      slots.push_back({r * std::cos(a), r * std::sin(a)});
    }
  } else {
    const double hl = t.size.x() / 2, hw = t.size.y() / 2;
    const double xs = hl >= 0.6 ? hl / 2 : 0.0;
    for (double x : (xs > 0 ? std::vector<double>{-xs, xs} : std::vector<double>{0.0})) {
      slots.push_back({x, hw + gap + 0.1});
      if (!kind.against_wall) slots.push_back({x, -(hw + gap + 0.1)});
    }
    if (!kind.against_wall) {
      slots.push_back({hl + gap + 0.1, 0.0});
      slots.push_back({-(hl + gap + 0.1), 0.0});
    }
  }
  // Random subset of the slots, each pulled out a random distance.
  for (std::size_t i = slots.size(); i > 1; --i)
    std::swap(slots[i - 1], slots[rng.integer(0, static_cast<int>(i) - 1)]);
  for (int k = 0; k < n && k < static_cast<int>(slots.size()); ++k) {
    const Slot& s = slots[k];
    const double pull = rng.uniform(0.0, 0.25);
    const Eigen::Vector2d dir = Eigen::Vector2d(s.lx, s.ly).normalized();
    const Eigen::Vector2d local = Eigen::Vector2d(s.lx, s.ly) + pull * dir;
    // Chair local +y must point at the table: yaw_chair such that (-sin, cos) = -dir.
    const Eigen::Vector2d dir_world = toWorld({0, 0}, t.yaw, dir.x(), dir.y());
    const double yaw = std::atan2(dir_world.x(), -dir_world.y());
    addChair(scene, layout, toWorld(t.center_xy, t.yaw, local.x(), local.y()), yaw,
             std::string(kind.name) == "bar", t.object, rng);
  }
}

bool addTable(SynthScene& scene, Layout& layout, const ApartmentParams& params,
              std::vector<Surface>& surfaces, Rng& rng) {
  // Kind by weight.
  double u = rng.uniform(), acc = 0.0;
  const TableKind* kind = &kTableKinds[0];
  for (const auto& k : kTableKinds) {
    acc += k.weight;
    if (u < acc) {
      kind = &k;
      break;
    }
  }
  double h_lo = std::max(kind->h_lo, params.table_height_min);
  double h_hi = std::min(kind->h_hi, params.table_height_max);
  if (h_lo > h_hi) {
    h_lo = params.table_height_min;
    h_hi = params.table_height_max;
  }
  TableTruth t;
  t.kind = kind->name;
  t.height = rng.uniform(h_lo, h_hi);
  t.shape = rng.chance(kind->p_round) ? TableShape::Round : TableShape::Rectangular;
  if (t.shape == TableShape::Round) {
    const double d = rng.uniform(kind->d_lo, kind->d_hi);
    t.size = {d, d};
  } else {
    t.size = {rng.uniform(kind->l_lo, kind->l_hi), rng.uniform(kind->w_lo, kind->w_hi)};
  }
  const auto walls = wallsOf(layout.room);
  bool placed = false;
  for (int attempt = 0; attempt < 200 && !placed; ++attempt) {
    Polygon2 clearance;  // where nothing else may stand (chairs and a passage)
    if (kind->against_wall) {
      const Wall& w = walls[rng.integer(0, 3)];
      if (w.length < t.size.x() + 0.2) continue;
      const double s = rng.uniform(t.size.x() / 2 + 0.05, w.length - t.size.x() / 2 - 0.05);
      t.center_xy = w.point(s, t.size.y() / 2 + 0.01);
      t.yaw = w.yaw();
      clearance = detail::rectangle(w.point(s, t.size.y() / 2 + 0.35), t.yaw, t.size.x() / 2 + 0.1,
                                    t.size.y() / 2 + 0.35);
    } else {
      t.center_xy = {rng.uniform(0.0, layout.room.x()), rng.uniform(0.0, layout.room.y())};
      if (rng.chance(0.7)) {  // mostly axis-aligned, a little off
        const double axis_yaw = rng.chance(0.5) ? 0.0 : M_PI / 2;
        t.yaw = axis_yaw + 0.03 * rng.normal();
      } else {
        t.yaw = rng.uniform(0.0, M_PI);
      }
      const double pad = kind->chairs_hi > 0 ? 0.75 : 0.55;
      clearance =
          t.shape == TableShape::Round
              ? detail::circle(t.center_xy, t.size.x() / 2 + pad, 16)
              : detail::rectangle(t.center_xy, t.yaw, t.size.x() / 2 + pad, t.size.y() / 2 + pad);
    }
    if (!layout.insideRoom(clearance, kind->against_wall ? -0.01 : 0.0)) continue;
    if (!layout.free(clearance)) continue;
    placed = true;
  }
  if (!placed) return false;

  t.top_polygon = t.shape == TableShape::Round
                      ? detail::circle(t.center_xy, t.size.x() / 2, 64)
                      : detail::rectangle(t.center_xy, t.yaw, t.size.x() / 2, t.size.y() / 2);
  const Material top = rng.chance(0.7) ? woodMaterial(rng) : laminateMaterial(rng);
  const Material legs =
      rng.chance(0.5) ? top : Material{jitter({140, 140, 145}, 0.2, rng), Texture::Plain, 0.2f};
  const double th = rng.uniform(0.025, 0.045);
  const double leg_h = t.height - th;
  std::vector<Primitive> parts;
  if (t.shape == TableShape::Round) {
    const double r = t.size.x() / 2;
    parts.push_back(cylinder(at(t.center_xy, t.height - th / 2), r, th / 2, top));
    const double base_h = 0.03;
    parts.push_back(
        cylinder(at(t.center_xy, base_h / 2), std::min(0.3, 0.6 * r), base_h / 2, legs));
    parts.push_back(cylinder(at(t.center_xy, base_h + (leg_h - base_h) / 2),
                             rng.uniform(0.035, 0.06), (leg_h - base_h) / 2, legs));
  } else {
    const double hl = t.size.x() / 2, hw = t.size.y() / 2;
    parts.push_back(box(at(t.center_xy, t.height - th / 2), t.yaw, {hl, hw, th / 2}, top));
    if (kind->against_wall && rng.chance(0.5)) {  // desk with two side panels
      for (int sx : {-1, 1})
        parts.push_back(box(at(toWorld(t.center_xy, t.yaw, sx * (hl - 0.04), 0.0), leg_h / 2),
                            t.yaw, {0.0125, hw - 0.03, leg_h / 2}, legs));
    } else {
      const double leg = rng.uniform(0.02, 0.035), inset = leg + rng.uniform(0.02, 0.06);
      for (int sx : {-1, 1})
        for (int sy : {-1, 1})
          parts.push_back(
              box(at(toWorld(t.center_xy, t.yaw, sx * (hl - inset), sy * (hw - inset)), leg_h / 2),
                  t.yaw, {leg, leg, leg_h / 2}, legs));
    }
  }
  t.id = static_cast<int>(scene.tables.size());
  t.object = addObject(scene, "table", Label::Table, std::move(parts));
  scene.objects[t.object].table = t.id;
  // Planning footprint: round tops as a circumscribed 16-gon (conservative).
  const Polygon2 footprint =
      t.shape == TableShape::Round
          ? detail::circle(t.center_xy, t.size.x() / 2 / std::cos(M_PI / 16), 16)
          : t.top_polygon;
  layout.solids.push_back({footprint, t.object});
  scene.obstacles.push_back({footprint, t.height, t.object});
  scene.tables.push_back(t);
  addChairs(scene, layout, t, *kind, rng);

  Surface s;
  // Keep objects 3 cm inside the edge.
  s.outline =
      t.shape == TableShape::Round
          ? detail::circle(t.center_xy, t.size.x() / 2 - 0.03, 32)
          : detail::rectangle(t.center_xy, t.yaw, t.size.x() / 2 - 0.03, t.size.y() / 2 - 0.03);
  s.z = t.height;
  s.max_height = 0.4;
  surfaces.push_back(s);
  return true;
}

// A piece of furniture with its back to a random wall: its footprint, centre
// and yaw (local +y into the room), or false when no free spot was found.
bool placeAgainstWall(const Layout& layout, double width, double depth, Rng& rng,
                      Eigen::Vector2d& center, double& yaw, Polygon2& footprint) {
  const auto walls = wallsOf(layout.room);
  for (int attempt = 0; attempt < 100; ++attempt) {
    const Wall& w = walls[rng.integer(0, 3)];
    if (w.length < width + 0.1) continue;
    const double s = rng.uniform(width / 2 + 0.02, w.length - width / 2 - 0.02);
    center = w.point(s, depth / 2 + 0.005);
    yaw = w.yaw();
    footprint = detail::rectangle(center, yaw, width / 2, depth / 2);
    // Leave 0.45 m in front free as well so nothing blocks the doors.
    const Polygon2 front = detail::rectangle(w.point(s, depth + 0.225), yaw, width / 2, 0.225);
    if (layout.insideRoom(footprint, -0.01) && layout.free(footprint) && layout.free(front))
      return true;
  }
  return false;
}

void addCabinet(SynthScene& scene, Layout& layout, std::vector<Surface>& surfaces, Rng& rng) {
  const double width = rng.uniform(0.4, 1.2), depth = rng.uniform(0.35, 0.6);
  const bool tall = rng.chance(0.4);
  const double height = tall ? rng.uniform(1.6, 2.1) : rng.uniform(0.5, 0.9);
  Eigen::Vector2d c;
  double yaw;
  Polygon2 footprint;
  if (!placeAgainstWall(layout, width, depth, rng, c, yaw, footprint)) return;
  const Rgb8 colors[] = {{235, 235, 228}, {160, 115, 75}, {90, 90, 95}, {200, 185, 160}};
  Material m{jitter(pick(colors, rng), 0.08, rng), Texture::Panel, 0.2f};
  std::vector<Primitive> parts;
  parts.push_back(box(at(c, height / 2), yaw, {width / 2, depth / 2, height / 2}, m));
  // Two handles either side of the door seam.
  const Material handle{{190, 190, 195}, Texture::Plain, 0.2f};
  for (int sx : {-1, 1})
    parts.push_back(
        box(at(toWorld(c, yaw, sx * 0.04, depth / 2 + 0.01), tall ? 1.0 : height - 0.12), yaw,
            {0.006, 0.01, 0.05}, handle));
  const int object = addObject(scene, "cabinet", Label::Cabinet, std::move(parts));
  layout.solids.push_back({footprint, object});
  scene.obstacles.push_back({footprint, height, object});
  if (!tall) {
    Surface s;
    s.outline = detail::rectangle(c, yaw, width / 2 - 0.03, depth / 2 - 0.03);
    s.z = height;
    s.max_height = 0.35;
    surfaces.push_back(s);
  }
}

void addShelf(SynthScene& scene, Layout& layout, std::vector<Surface>& surfaces, Rng& rng) {
  const double width = rng.uniform(0.6, 1.2), depth = rng.uniform(0.25, 0.4);
  const double height = rng.uniform(1.0, 2.0);
  Eigen::Vector2d c;
  double yaw;
  Polygon2 footprint;
  if (!placeAgainstWall(layout, width, depth, rng, c, yaw, footprint)) return;
  const Material m = rng.chance(0.6) ? woodMaterial(rng) : laminateMaterial(rng);
  const double th = 0.02, hw = width / 2, hd = depth / 2;
  std::vector<Primitive> parts;
  for (int sx : {-1, 1})  // side panels
    parts.push_back(box(at(toWorld(c, yaw, sx * (hw - th / 2), 0.0), height / 2), yaw,
                        {th / 2, hd, height / 2}, m));
  parts.push_back(box(at(toWorld(c, yaw, 0.0, -hd + 0.005), height / 2), yaw,
                      {hw - th, 0.005, height / 2}, m));  // back
  const int boards = rng.integer(3, 5);                   // including bottom and top
  const double spacing = (height - th) / (boards - 1);
  for (int b = 0; b < boards; ++b) {
    const double z = b * spacing + th / 2;
    parts.push_back(box(at(c, z), yaw, {hw - th, hd, th / 2}, m));
    Surface s;
    s.outline = detail::rectangle(toWorld(c, yaw, 0.0, 0.01), yaw, hw - th - 0.01, hd - 0.03);
    s.z = z + th / 2;
    s.max_height = b + 1 < boards ? spacing - th - 0.02 : 0.3;
    surfaces.push_back(s);
  }
  const int object = addObject(scene, "shelf", Label::Cabinet, std::move(parts));
  layout.solids.push_back({footprint, object});
  scene.obstacles.push_back({footprint, height, object});
}

// Doors and windows: thin slabs on the walls, labelled Wall.
void addWallOpenings(SynthScene& scene, Layout& layout, const ApartmentParams& params, Rng& rng) {
  const auto walls = wallsOf(layout.room);
  std::array<std::vector<std::pair<double, double>>, 4> used;  // intervals along each wall
  auto claim = [&](int w, double width) -> double {
    for (int attempt = 0; attempt < 50; ++attempt) {
      if (walls[w].length < width + 0.6) return -1;
      const double s0 = rng.uniform(0.3, walls[w].length - 0.3 - width);
      bool ok = true;
      for (const auto& [a, b] : used[w]) ok = ok && (s0 + width + 0.2 < a || s0 > b + 0.2);
      if (ok) {
        used[w].push_back({s0, s0 + width});
        return s0;
      }
    }
    return -1;
  };
  const int doors = rng.integer(params.doors_min, params.doors_max);
  for (int i = 0; i < doors; ++i) {
    const int w = rng.integer(0, 3);
    const double width = rng.uniform(0.8, 0.92), height = rng.uniform(2.0, 2.1);
    const double s0 = claim(w, width);
    if (s0 < 0) continue;
    const Wall& wall = walls[w];
    const double s = s0 + width / 2;
    Material m = rng.chance(0.5)
                     ? woodMaterial(rng)
                     : Material{jitter({238, 238, 232}, 0.05, rng), Texture::Panel, 0.2f};
    std::vector<Primitive> parts{
        box(at(wall.point(s, 0.015), std::min(height, layout.room.z()) / 2), wall.yaw(),
            {width / 2, 0.015, std::min(height, layout.room.z()) / 2}, m)};
    addObject(scene, "door", Label::Wall, std::move(parts));
    layout.keepouts.push_back(
        detail::rectangle(wall.point(s, 0.5), wall.yaw(), width / 2 + 0.05, 0.5));
  }
  const int windows = rng.integer(params.windows_min, params.windows_max);
  for (int i = 0; i < windows; ++i) {
    const int w = rng.integer(0, 3);
    const double width = rng.uniform(0.8, 1.6), height = rng.uniform(1.0, 1.3);
    const double bottom = rng.uniform(0.8, 1.0);
    if (bottom + height > layout.room.z() - 0.1) continue;
    const double s0 = claim(w, width);
    if (s0 < 0) continue;
    const Wall& wall = walls[w];
    Material m{jitter({185, 205, 220}, 0.05, rng), Texture::Panel, 0.2f};
    std::vector<Primitive> parts{box(at(wall.point(s0 + width / 2, 0.02), bottom + height / 2),
                                     wall.yaw(), {width / 2, 0.02, height / 2}, m)};
    addObject(scene, "window", Label::Wall, std::move(parts));
  }
}

SynthScene tryApartment(Rng& rng, const ApartmentParams& params) {
  const Eigen::Vector3d size =
      uniform3(rng, {params.room_x_min, params.room_y_min, params.ceiling_min},
               {params.room_x_max, params.room_y_max, params.ceiling_max});
  SynthScene scene = makeEmptyRoom(size);
  // Floor: boards, tiles or carpet; walls a pale paint; ceiling white.
  const double floor_kind = rng.uniform();
  if (floor_kind < 0.45) {
    const Rgb8 woods[] = {{165, 120, 80}, {190, 150, 105}, {120, 85, 55}, {210, 185, 150}};
    scene.floor_material = {jitter(pick(woods, rng), 0.1, rng), Texture::Planks,
                            static_cast<float>(rng.uniform(0.12, 0.2))};
  } else if (floor_kind < 0.75) {
    const Rgb8 tiles[] = {{200, 195, 185}, {150, 150, 150}, {225, 215, 200}, {110, 105, 100}};
    scene.floor_material = {jitter(pick(tiles, rng), 0.1, rng), Texture::Tiles,
                            static_cast<float>(rng.uniform(0.3, 0.6))};
  } else {
    const Rgb8 carpets[] = {{120, 115, 110}, {80, 90, 120}, {170, 150, 120}, {100, 60, 55}};
    scene.floor_material = {jitter(pick(carpets, rng), 0.1, rng), Texture::Carpet, 0.01f};
  }
  const Rgb8 paints[] = {
      {235, 232, 222}, {220, 228, 235}, {238, 225, 205}, {215, 230, 215}, {240, 240, 240}};
  scene.wall_material = {jitter(pick(paints, rng), 0.04, rng), Texture::Plain, 0.2f};
  scene.ceiling_material = {jitter({245, 245, 242}, 0.02, rng), Texture::Plain, 0.2f};

  Layout layout;
  layout.room = size;
  addWallOpenings(scene, layout, params, rng);
  std::vector<Surface> surfaces;
  const int tables = rng.integer(params.tables_min, params.tables_max);
  for (int i = 0; i < tables; ++i) addTable(scene, layout, params, surfaces, rng);
  const int cabinets = rng.integer(params.cabinets_min, params.cabinets_max);
  for (int i = 0; i < cabinets; ++i) addCabinet(scene, layout, surfaces, rng);
  const int shelves = rng.integer(params.shelves_min, params.shelves_max);
  for (int i = 0; i < shelves; ++i) addShelf(scene, layout, surfaces, rng);
  // Small objects: on every table top, a few on shelves and low cabinets.
  for (auto& s : surfaces) {
    const bool table_top = s.max_height >= 0.4;
    const int n = table_top
                      ? rng.integer(params.objects_per_table_min, params.objects_per_table_max)
                      : rng.integer(0, 3);
    for (int k = 0; k < n; ++k) placeSmallObject(scene, s, rng, !table_top && rng.chance(0.5));
  }
  return scene;
}

}  // namespace

void validate(const ApartmentParams& p) {
  checkRange("room_x", p.room_x_min, p.room_x_max, 3.0, 20.0);
  checkRange("room_y", p.room_y_min, p.room_y_max, 3.0, 20.0);
  checkRange("ceiling", p.ceiling_min, p.ceiling_max, 2.2, 5.0);
  checkRange("tables", p.tables_min, p.tables_max, 1, 10);
  checkRange("table_height", p.table_height_min, p.table_height_max, 0.3, 1.3);
  checkRange("cabinets", p.cabinets_min, p.cabinets_max, 0, 10);
  checkRange("shelves", p.shelves_min, p.shelves_max, 0, 10);
  checkRange("doors", p.doors_min, p.doors_max, 0, 4);
  checkRange("windows", p.windows_min, p.windows_max, 0, 6);
  checkRange("objects_per_table", p.objects_per_table_min, p.objects_per_table_max, 0, 20);
}

SynthScene makeEmptyRoom(const Eigen::Vector3d& room_size) {
  if (!room_size.allFinite() || (room_size.array() <= 0.5).any() ||
      (room_size.array() > 50.0).any()) {
    std::ostringstream msg;
    msg << "synth: absurd room size " << room_size.transpose() << " (each side 0.5..50 m)";
    throw Error(msg.str());
  }
  SynthScene scene;
  scene.room_size = room_size;
  scene.floor_material = {{170, 140, 110}, Texture::Plain, 0.2f};
  scene.wall_material = {{230, 230, 225}, Texture::Plain, 0.2f};
  scene.ceiling_material = {{245, 245, 245}, Texture::Plain, 0.2f};
  scene.objects.push_back({"floor", Label::Floor, -1});
  scene.objects.push_back({"ceiling", Label::Ceiling, -1});
  for (int w = 0; w < 4; ++w) scene.objects.push_back({"wall", Label::Wall, -1});
  return scene;
}

int addObject(SynthScene& scene, const std::string& kind, Label label,
              std::vector<Primitive> parts) {
  const int index = static_cast<int>(scene.objects.size());
  scene.objects.push_back({kind, label, -1});
  for (auto& p : parts) {
    p.object = index;
    scene.primitives.push_back(p);
  }
  return index;
}

SynthScene makeApartment(std::uint64_t seed, const ApartmentParams& params) {
  validate(params);
  // A few layouts fail to fit a reachable table (small room, unlucky draws);
  // the next attempt uses a stream derived from the same seed, so the result
  // is still a pure function of the seed.
  for (int attempt = 0; attempt < 50; ++attempt) {
    Rng rng(detail::hash3(seed, static_cast<std::uint64_t>(attempt), 0xa9a27e47ULL));
    SynthScene scene = tryApartment(rng, params);
    scene.seed = seed;
    if (static_cast<int>(scene.tables.size()) < params.tables_min) continue;
    if (detail::hasReachableTable(scene)) return scene;
  }
  throw Error("synth: no apartment with a reachable table for seed " + std::to_string(seed) +
              " after 50 attempts (room too small for the requested furniture?)");
}

}  // namespace findmug::synth
