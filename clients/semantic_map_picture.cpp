// The semantic map drawn top-down; see semantic_map_picture.hpp.
#include "semantic_map_picture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "picture.hpp"

namespace findmug::clients {

namespace {

constexpr Rgb8 kWhite{255, 255, 255}, kBlack{0, 0, 0}, kGrid{225, 225, 225}, kRobot{30, 110, 255};

bool shown(const io::SemanticMapVoxel& v, float voxel_size_m) {
  return v.label < kNumLabels && v.label != static_cast<std::uint8_t>(Label::Ceiling) &&
         static_cast<float>(v.k) * voxel_size_m < kTopDownMaxHeightM;
}

bool haveTables(const io::TablesMessage* table_map) {
  return table_map != nullptr && table_map->map_pose.has_value() &&
         table_map->map_tables.size() == table_map->tables.size();
}

}  // namespace

TopDownCells topDownCells(const io::SemanticMapMessage& map) {
  TopDownCells out;
  out.voxel_size_m = map.voxel_size_m;
  int min_i = std::numeric_limits<int>::max(), max_i = std::numeric_limits<int>::min();
  int min_j = min_i, max_j = max_i;
  for (const auto& v : map.voxels) {
    if (!shown(v, map.voxel_size_m)) continue;
    min_i = std::min(min_i, int{v.i}), max_i = std::max(max_i, int{v.i});
    min_j = std::min(min_j, int{v.j}), max_j = std::max(max_j, int{v.j});
  }
  if (min_i > max_i) return out;
  out.min_i = min_i;
  out.max_j = max_j;
  out.width = max_i - min_i + 1;
  out.height = max_j - min_j + 1;
  const std::size_t n = static_cast<std::size_t>(out.width) * out.height;
  out.label.assign(n, kNoCell);
  out.confidence.assign(n, 0);
  std::vector<int> top_k(n, std::numeric_limits<int>::min());
  for (const auto& v : map.voxels) {
    if (!shown(v, map.voxel_size_m)) continue;
    const std::size_t cell =
        static_cast<std::size_t>(max_j - v.j) * out.width + static_cast<std::size_t>(v.i - min_i);
    if (v.k <= top_k[cell]) continue;
    if (top_k[cell] == std::numeric_limits<int>::min()) ++out.cells;
    top_k[cell] = v.k;
    out.label[cell] = v.label;
    out.confidence[cell] = v.confidence;
  }
  return out;
}

Rgb8 shadedLabelColor(std::uint8_t label, std::uint8_t confidence) {
  if (label >= kNumLabels) return kWhite;
  const Rgb8 c = kLabelColors[label];
  const double keep = 0.25 + 0.75 * confidence / 255.0;
  auto mix = [keep](std::uint8_t channel) {
    return static_cast<std::uint8_t>(std::lround(255.0 - keep * (255.0 - channel)));
  };
  return {mix(c.r), mix(c.g), mix(c.b)};
}

TopDownView semanticMapView(const TopDownCells& cells, const io::TablesMessage* table_map,
                            int size_px) {
  double x0 = std::numeric_limits<double>::max(), y0 = x0, x1 = -x0, y1 = -x0;
  auto grow = [&](double x, double y) {
    x0 = std::min(x0, x - 0.5), x1 = std::max(x1, x + 0.5);
    y0 = std::min(y0, y - 0.5), y1 = std::max(y1, y + 0.5);
  };
  const double voxel = cells.voxel_size_m;
  if (cells.cells > 0) {
    grow((cells.min_i - 0.5) * voxel, (cells.max_j - cells.height + 0.5) * voxel);
    grow((cells.min_i + cells.width - 0.5) * voxel, (cells.max_j + 0.5) * voxel);
  }
  if (haveTables(table_map)) {
    grow(table_map->map_pose->pose.x, table_map->map_pose->pose.y);
    for (const auto& t : table_map->map_tables) {
      for (const auto& p : t.hull) grow(p.x(), p.y());
    }
  }
  if (x0 > x1) grow(0.0, 0.0);
  TopDownView v;
  const double span = std::max(x1 - x0, y1 - y0);
  v.scale = (size_px - 2 * v.margin) / span;
  v.min_x = (x0 + x1) / 2 - span / 2;
  v.max_y = (y0 + y1) / 2 + span / 2;
  return v;
}

Image<Rgb8> semanticMapPng(const io::SemanticMapMessage& map, const io::TablesMessage* table_map,
                           int size_px) {
  const TopDownCells cells = topDownCells(map);
  const bool have_tables = haveTables(table_map);
  const TopDownView v = semanticMapView(cells, table_map, size_px);
  const double voxel = cells.voxel_size_m;
  const double span = (size_px - 2 * v.margin) / v.scale;

  Canvas canvas(size_px, size_px, kWhite);
  for (int g = static_cast<int>(std::floor(v.min_x));
       g <= static_cast<int>(std::ceil(v.min_x + span)); ++g) {
    const double x = v.px(g, 0).x();
    if (x >= v.margin && x <= size_px - v.margin)
      canvas.line(x, v.margin, x, size_px - v.margin, kGrid);
  }
  for (int g = static_cast<int>(std::floor(v.max_y - span));
       g <= static_cast<int>(std::ceil(v.max_y)); ++g) {
    const double y = v.px(0, g).y();
    if (y >= v.margin && y <= size_px - v.margin)
      canvas.line(v.margin, y, size_px - v.margin, y, kGrid);
  }
  // Cells: squares of one voxel edge, corner to corner, so that neighbours meet.
  for (int row = 0; row < cells.height; ++row) {
    for (int col = 0; col < cells.width; ++col) {
      const std::size_t cell = static_cast<std::size_t>(row) * cells.width + col;
      if (cells.label[cell] == kNoCell) continue;
      const int i = cells.min_i + col, j = cells.max_j - row;
      const Eigen::Vector2d a = v.px((i - 0.5) * voxel, (j + 0.5) * voxel);
      const Eigen::Vector2d b = v.px((i + 0.5) * voxel, (j - 0.5) * voxel);
      const int xa = static_cast<int>(std::lround(a.x())),
                ya = static_cast<int>(std::lround(a.y()));
      const int xb = static_cast<int>(std::lround(b.x())),
                yb = static_cast<int>(std::lround(b.y()));
      canvas.fillRect(xa, ya, std::max(1, xb - xa), std::max(1, yb - ya),
                      shadedLabelColor(cells.label[cell], cells.confidence[cell]));
    }
  }
  if (have_tables) {
    for (std::size_t t = 0; t < table_map->tables.size(); ++t) {
      const auto& hull = table_map->map_tables[t].hull;
      for (std::size_t k = 0; k < hull.size(); ++k) {
        const auto a = v.px(hull[k].x(), hull[k].y());
        const auto b = v.px(hull[(k + 1) % hull.size()].x(), hull[(k + 1) % hull.size()].y());
        canvas.line(a.x(), a.y(), b.x(), b.y(), kBlack, 2);
      }
      // "T3" and, when the semantic map counted them, "12F 5V" (frames, viewpoints).
      const auto c = v.px(table_map->map_tables[t].center.x(), table_map->map_tables[t].center.y());
      char id[32];  // snprintf: GCC 12 warns (-Wrestrict) on "T" + std::to_string here
      std::snprintf(id, sizeof(id), "T%d", table_map->tables[t].id);
      canvas.fillRect(static_cast<int>(c.x()) - 2, static_cast<int>(c.y()) - 9,
                      Canvas::textWidth(id, 2) + 4, Canvas::textHeight(2) + 4, kWhite);
      canvas.text(static_cast<int>(c.x()), static_cast<int>(c.y()) - 7, id, kBlack, 2);
      if (t < table_map->map_info.size() && table_map->map_info[t].viewpoints > 0) {
        char support[48];
        std::snprintf(support, sizeof(support), "%dF %dV", table_map->map_info[t].sightings,
                      table_map->map_info[t].viewpoints);
        canvas.fillRect(static_cast<int>(c.x()) - 2, static_cast<int>(c.y()) + 8,
                        Canvas::textWidth(support) + 4, Canvas::textHeight() + 4, kWhite);
        canvas.text(static_cast<int>(c.x()), static_cast<int>(c.y()) + 10, support, kBlack);
      }
    }
    const auto& pose = table_map->map_pose->pose;
    const auto r = v.px(pose.x, pose.y);
    canvas.disc(r.x(), r.y(), 10, kRobot);
    canvas.line(r.x(), r.y(), r.x() + 22 * std::cos(pose.yaw), r.y() - 22 * std::sin(pose.yaw),
                kRobot, 3);
  }
  char title[160];
  std::snprintf(title, sizeof(title), "semantic map seq %lld: %zu voxels, %lld frames, %zu tables",
                static_cast<long long>(map.seq), map.voxels.size(),
                static_cast<long long>(map.frames), have_tables ? table_map->tables.size() : 0);
  canvas.text(8, 8, title, kBlack);
  canvas.text(8, size_px - 14, "grid 1 m; x right, y up; faded = less sure", kBlack);
  return canvas.image();
}

}  // namespace findmug::clients
