#include "picture.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "findmug/ground/ground.hpp"
#include "findmug/map/visiting_order.hpp"

namespace findmug::clients {
namespace {

// 5x7 glyphs, one byte per row, bit 4 = leftmost column.
struct Glyph {
  char c;
  std::array<std::uint8_t, 7> rows;
};
constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'#', {0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
};

const Glyph* glyphOf(char c) {
  const char upper = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  for (const auto& g : kFont) {
    if (g.c == upper) return &g;
  }
  return nullptr;  // space and anything unknown: blank
}

constexpr Rgb8 kWhite{255, 255, 255}, kBlack{0, 0, 0}, kReachable{40, 200, 60},
    kUnreachable{220, 40, 40}, kHull{255, 255, 255}, kRobot{30, 110, 255}, kGrid{225, 225, 225},
    kPanel{245, 245, 245}, kTableFill{150, 215, 150};

// One marker style for search positions everywhere: a disc with its number (reachable)
// or a red disc with a cross (unreachable).
void drawPositionMarker(Canvas& canvas, double x, double y, int order, double radius) {
  canvas.disc(x, y, radius + 1.5, kBlack);
  canvas.disc(x, y, radius, order > 0 ? kReachable : kUnreachable);
  if (order > 0) {
    const std::string label = std::to_string(order);
    const int scale = radius >= 9 ? 2 : 1;
    canvas.text(static_cast<int>(std::lround(x)) - Canvas::textWidth(label, scale) / 2,
                static_cast<int>(std::lround(y)) - Canvas::textHeight(scale) / 2, label, kBlack,
                scale);
  } else {
    const double d = radius * 0.55;
    canvas.line(x - d, y - d, x + d, y + d, kWhite, 2);
    canvas.line(x - d, y + d, x + d, y - d, kWhite, 2);
  }
}

// "T<id>" (built with snprintf: GCC 12 warns falsely on "T" + std::to_string).
std::string tableName(int id) {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "T%d", id);
  return buffer;
}

// A search position the camera cannot see (behind a surface): a ring in the marker's
// colour, the number (if any) inside.
void drawHiddenMarker(Canvas& canvas, double x, double y, int order, double radius) {
  canvas.circle(x, y, radius, kBlack, 4);
  canvas.circle(x, y, radius, order > 0 ? kReachable : kUnreachable, 2);
  if (order > 0) {
    const std::string label = std::to_string(order);
    canvas.text(static_cast<int>(std::lround(x)) - Canvas::textWidth(label, 1) / 2,
                static_cast<int>(std::lround(y)) - 3, label, kWhite, 1);
  }
}

// "O<id>" for an object candidate (snprintf for the reason tableName gives).
std::string objectName(int id) {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "O%d", id);
  return buffer;
}

// An object candidate: a disc in its own mean colour, so that the marker says which thing it
// is, inside a white ring that stands out on any label colour.
void drawObjectMarker(Canvas& canvas, double x, double y, Rgb8 colour, double radius) {
  canvas.disc(x, y, radius + 4.5, kBlack);
  canvas.disc(x, y, radius + 3, kWhite);
  canvas.disc(x, y, radius + 1, kBlack);
  canvas.disc(x, y, radius, colour);
}

Rgb8 meanColour(const TableObject& o) {
  auto channel = [](float v) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 255.0f)));
  };
  return Rgb8{channel(o.mean_rgb.x()), channel(o.mean_rgb.y()), channel(o.mean_rgb.z())};
}

}  // namespace

Canvas::Canvas(int width, int height, Rgb8 background)
    : image_{width, height,
             std::vector<Rgb8>(static_cast<std::size_t>(width) * height, background)} {}

void Canvas::pixel(int x, int y, Rgb8 colour) {
  if (x < 0 || y < 0 || x >= image_.width || y >= image_.height) return;
  image_.pixels[static_cast<std::size_t>(y) * image_.width + x] = colour;
}

void Canvas::fillRect(int x, int y, int w, int h, Rgb8 colour) {
  for (int yy = std::max(0, y); yy < std::min(image_.height, y + h); ++yy) {
    for (int xx = std::max(0, x); xx < std::min(image_.width, x + w); ++xx) pixel(xx, yy, colour);
  }
}

void Canvas::line(double x0, double y0, double x1, double y1, Rgb8 colour, int thickness) {
  const double length = std::hypot(x1 - x0, y1 - y0);
  const int steps = std::max(1, static_cast<int>(std::ceil(length * 2)));
  const double r = thickness / 2.0;
  for (int i = 0; i <= steps; ++i) {
    const double t = static_cast<double>(i) / steps;
    const double x = x0 + t * (x1 - x0), y = y0 + t * (y1 - y0);
    if (thickness <= 1) {
      pixel(static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y)), colour);
    } else {
      disc(x, y, r, colour);
    }
  }
}

void Canvas::disc(double cx, double cy, double radius, Rgb8 colour) {
  const int x0 = static_cast<int>(std::floor(cx - radius)),
            x1 = static_cast<int>(std::ceil(cx + radius));
  const int y0 = static_cast<int>(std::floor(cy - radius)),
            y1 = static_cast<int>(std::ceil(cy + radius));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= radius * radius) pixel(x, y, colour);
    }
  }
}

void Canvas::circle(double cx, double cy, double radius, Rgb8 colour, int thickness) {
  const int steps = std::max(16, static_cast<int>(radius * 8));
  for (int i = 0; i < steps; ++i) {
    const double a0 = 2 * M_PI * i / steps, a1 = 2 * M_PI * (i + 1) / steps;
    line(cx + radius * std::cos(a0), cy + radius * std::sin(a0), cx + radius * std::cos(a1),
         cy + radius * std::sin(a1), colour, thickness);
  }
}

void Canvas::text(int x, int y, const std::string& text, Rgb8 colour, int scale) {
  for (std::size_t k = 0; k < text.size(); ++k) {
    const Glyph* g = glyphOf(text[k]);
    if (g == nullptr) continue;
    const int gx = x + static_cast<int>(k) * 6 * scale;
    for (int row = 0; row < 7; ++row) {
      for (int col = 0; col < 5; ++col) {
        if (g->rows[row] & (0x10 >> col))
          fillRect(gx + col * scale, y + row * scale, scale, scale, colour);
      }
    }
  }
}

void Canvas::paste(const Image<Rgb8>& other, int x, int y) {
  for (int yy = 0; yy < other.height; ++yy) {
    for (int xx = 0; xx < other.width; ++xx) {
      pixel(x + xx, y + yy, other.pixels[static_cast<std::size_t>(yy) * other.width + xx]);
    }
  }
}

Image<Rgb8> withLegend(const Image<Rgb8>& overlay) {
  const int panel = 150, row = 22;
  Canvas canvas(overlay.width + panel, std::max(overlay.height, row * 16), kPanel);
  canvas.paste(overlay, 0, 0);
  const int x = overlay.width + 10;
  int y = 10;
  canvas.text(x, y, "LABELS", kBlack, 2);
  y += 24;
  for (int id = 0; id <= kNumLabels; ++id) {
    const Rgb8 colour = id < kNumLabels ? kLabelColors[id] : kVoidColor;
    canvas.fillRect(x - 1, y - 1, 18, 16, kBlack);
    canvas.fillRect(x, y, 16, 14, colour);
    canvas.text(x + 24, y + 1, id < kNumLabels ? std::string(kLabelNames[id]) : "void (no depth)",
                kBlack, 1);
    y += row;
  }
  y += 6;
  canvas.text(x, y, "SEARCH POSITIONS", kBlack, 1);
  y += 18;
  drawPositionMarker(canvas, x + 8, y + 6, 1, 8);
  canvas.text(x + 24, y + 3, "reachable, order", kBlack, 1);
  y += row;
  drawPositionMarker(canvas, x + 8, y + 6, 0, 8);
  canvas.text(x + 24, y + 3, "unreachable", kBlack, 1);
  y += row;
  drawHiddenMarker(canvas, x + 8, y + 6, 0, 8);
  canvas.text(x + 24, y + 3, "hidden from view", kBlack, 1);
  y += row;
  canvas.line(x, y + 6, x + 16, y + 6, kHull, 3);
  canvas.line(x, y + 6, x + 16, y + 6, kBlack, 1);
  canvas.text(x + 24, y + 3, "table top hull", kBlack, 1);
  y += row;
  drawObjectMarker(canvas, x + 8, y + 6, Rgb8{200, 60, 40}, 3);
  canvas.text(x + 24, y + 3, "object on a table", kBlack, 1);
  return canvas.image();
}

std::vector<NumberedPosition> numberedPositions(const io::TablesMessage& message, bool map_frame) {
  const bool use_map = map_frame && message.map_pose && !message.map_tables.empty();
  std::vector<NumberedPosition> reachable, unreachable;
  for (std::size_t t = 0; t < message.tables.size(); ++t) {
    const auto& positions =
        use_map ? message.map_tables[t].search_positions : message.tables[t].search_positions;
    for (const auto& p : positions) {
      (p.reachable ? reachable : unreachable).push_back({message.tables[t].id, p, 0});
    }
  }
  Eigen::Vector2f robot = Eigen::Vector2f::Zero();
  if (use_map) {
    robot = Eigen::Vector2f(static_cast<float>(message.map_pose->pose.x),
                            static_cast<float>(message.map_pose->pose.y));
  }
  std::vector<Eigen::Vector2f> points;
  for (const auto& r : reachable) points.push_back(r.position.xy);
  const std::vector<int> order = visitingOrder(robot, points);
  for (std::size_t k = 0; k < order.size(); ++k)
    reachable[order[k]].order = static_cast<int>(k) + 1;
  reachable.insert(reachable.end(), unreachable.begin(), unreachable.end());
  return reachable;
}

int drawTablesInImage(Canvas& canvas, const io::TablesMessage& tables, const CameraIntrinsics& k,
                      const CameraExtrinsics& extrinsics,
                      const std::vector<std::uint16_t>* depth_mm) {
  return drawTablesInImage(canvas, tables, k,
                           groundFromExtrinsics(extrinsics).camera_to_ground.cast<double>(),
                           depth_mm);
}

int drawTablesInImage(Canvas& canvas, const io::TablesMessage& tables, const CameraIntrinsics& k,
                      const Eigen::Isometry3d& camera_to_base,
                      const std::vector<std::uint16_t>* depth_mm) {
  const Eigen::Isometry3f ground_to_camera = camera_to_base.cast<float>().inverse();
  auto project = [&](float x, float y, float z, Eigen::Vector2d& pixel) {
    const Eigen::Vector3f c = ground_to_camera * Eigen::Vector3f(x, y, z);
    if (c.z() < 0.1f) return false;  // behind or at the camera
    pixel = Eigen::Vector2d(k.fx * c.x() / c.z() + k.cx, k.fy * c.y() / c.z() + k.cy);
    return true;
  };
  int drawn = 0;
  for (const auto& table : tables.tables) {
    bool any = false;
    const std::size_t n = table.hull.size();
    for (std::size_t i = 0; i < n; ++i) {
      const auto& a = table.hull[i];
      const auto& b = table.hull[(i + 1) % n];
      Eigen::Vector2d pa, pb;
      if (!project(a.x(), a.y(), table.top_height, pa) ||
          !project(b.x(), b.y(), table.top_height, pb)) {
        continue;
      }
      canvas.line(pa.x(), pa.y(), pb.x(), pb.y(), kBlack, 5);
      canvas.line(pa.x(), pa.y(), pb.x(), pb.y(), kHull, 3);
      any = true;
    }
    Eigen::Vector2d centre;
    if (project(table.center.x(), table.center.y(), table.top_height, centre)) {
      const std::string id = tableName(table.id);
      canvas.fillRect(static_cast<int>(centre.x()) - 3, static_cast<int>(centre.y()) - 3,
                      Canvas::textWidth(id, 2) + 6, Canvas::textHeight(2) + 6, kWhite);
      canvas.text(static_cast<int>(centre.x()), static_cast<int>(centre.y()), id, kBlack, 2);
    }
    drawn += any ? 1 : 0;
  }
  const bool have_depth =
      depth_mm != nullptr &&
      depth_mm->size() == static_cast<std::size_t>(canvas.width()) * canvas.height();
  for (const auto& p : numberedPositions(tables, false)) {
    Eigen::Vector2d pixel;
    if (!project(p.position.xy.x(), p.position.xy.y(), 0.0f, pixel)) continue;
    const int u = static_cast<int>(std::lround(pixel.x())),
              v = static_cast<int>(std::lround(pixel.y()));
    bool hidden = false;
    if (have_depth && u >= 0 && v >= 0 && u < canvas.width() && v < canvas.height()) {
      const std::uint16_t seen = (*depth_mm)[static_cast<std::size_t>(v) * canvas.width() + u];
      const Eigen::Vector3f c =
          ground_to_camera * Eigen::Vector3f(p.position.xy.x(), p.position.xy.y(), 0.0f);
      hidden = seen > 0 && c.z() > seen / 1000.0f + 0.15f;  // 15 cm: depth noise at a few metres
    }
    if (hidden) {
      drawHiddenMarker(canvas, pixel.x(), pixel.y(), p.order, 10);
    } else {
      drawPositionMarker(canvas, pixel.x(), pixel.y(), p.order, 10);
    }
  }
  return drawn;
}

int drawObjectsInImage(Canvas& canvas, const io::ObjectsMessage& objects, const CameraIntrinsics& k,
                       const CameraExtrinsics& extrinsics) {
  return drawObjectsInImage(canvas, objects, k,
                            groundFromExtrinsics(extrinsics).camera_to_ground.cast<double>());
}

int drawObjectsInImage(Canvas& canvas, const io::ObjectsMessage& objects, const CameraIntrinsics& k,
                       const Eigen::Isometry3d& camera_to_base) {
  const Eigen::Isometry3f base_to_camera = camera_to_base.cast<float>().inverse();
  int drawn = 0;
  for (const TableObject& o : objects.objects) {
    const Eigen::Vector3f c = base_to_camera * o.centroid;
    if (c.z() < 0.1f) continue;  // behind or at the camera
    const double u = k.fx * c.x() / c.z() + k.cx, v = k.fy * c.y() / c.z() + k.cy;
    drawObjectMarker(canvas, u, v, meanColour(o), 5);
    const std::string id = objectName(o.id);
    const int x = static_cast<int>(std::lround(u)) + 12, y = static_cast<int>(std::lround(v)) - 4;
    canvas.fillRect(x - 2, y - 2, Canvas::textWidth(id) + 4, Canvas::textHeight() + 4, kWhite);
    canvas.text(x, y, id, kBlack);
    ++drawn;
  }
  return drawn;
}

namespace {

// What the top-down view shows, in one frame (map or base), and where the robot is.
struct TopDown {
  struct Table {
    int id = 0;
    std::vector<Eigen::Vector2d> hull;
    Eigen::Vector2d center = Eigen::Vector2d::Zero();
  };
  std::vector<Table> tables;
  std::vector<NumberedPosition> positions;
  Eigen::Vector2d robot = Eigen::Vector2d::Zero();
  double robot_yaw = 0.0;
  bool map = false;
  // metres -> pixels
  double scale = 100.0, min_x = 0.0, max_y = 0.0;
  int size = 600, margin = 40;
  Eigen::Vector2d px(const Eigen::Vector2d& p) const {
    return {margin + (p.x() - min_x) * scale, margin + (max_y - p.y()) * scale};
  }
};

TopDown topDown(const io::TablesMessage& m, int size) {
  TopDown v;
  v.size = size;
  v.map = m.map_pose.has_value() && m.map_tables.size() == m.tables.size();
  for (std::size_t t = 0; t < m.tables.size(); ++t) {
    TopDown::Table table;
    table.id = m.tables[t].id;
    if (v.map) {
      table.hull = m.map_tables[t].hull;
      table.center = m.map_tables[t].center;
    } else {
      for (const auto& p : m.tables[t].hull) table.hull.push_back(p.cast<double>());
      table.center = m.tables[t].center.cast<double>();
    }
    v.tables.push_back(table);
  }
  v.positions = numberedPositions(m, v.map);
  if (v.map) {
    v.robot = {m.map_pose->pose.x, m.map_pose->pose.y};
    v.robot_yaw = m.map_pose->pose.yaw;
  }
  // Bounds of everything, 0.5 m around, square, at most 150 px per metre.
  double x0 = v.robot.x() - 0.5, x1 = v.robot.x() + 0.5, y0 = v.robot.y() - 0.5,
         y1 = v.robot.y() + 0.5;
  auto grow = [&](double x, double y) {
    x0 = std::min(x0, x - 0.5), x1 = std::max(x1, x + 0.5);
    y0 = std::min(y0, y - 0.5), y1 = std::max(y1, y + 0.5);
  };
  for (const auto& t : v.tables) {
    for (const auto& p : t.hull) grow(p.x(), p.y());
  }
  for (const auto& p : v.positions) grow(p.position.xy.x(), p.position.xy.y());
  const double span = std::max(x1 - x0, y1 - y0);
  v.scale = std::min(150.0, (size - 2 * v.margin) / span);
  v.min_x = (x0 + x1) / 2 - span / 2;
  v.max_y = (y0 + y1) / 2 + span / 2;
  return v;
}

std::string xmlEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else
      out += c;
  }
  return out;
}

std::string title(const TopDown& v, const io::TablesMessage& m) {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), "%s frame, seq %lld: %zu tables, %zu search positions",
                v.map ? "map" : "robot base", static_cast<long long>(m.seq), v.tables.size(),
                v.positions.size());
  return buffer;
}

}  // namespace

Image<Rgb8> tableMapPng(const io::TablesMessage& tables, int size_px) {
  const TopDown v = topDown(tables, size_px);
  Canvas canvas(size_px, size_px, kWhite);
  // 1 m grid.
  const double metres = (size_px - 2 * v.margin) / v.scale;
  for (int i = static_cast<int>(std::floor(v.min_x));
       i <= static_cast<int>(std::ceil(v.min_x + metres)); ++i) {
    const double x = v.px({i, 0}).x();
    if (x >= v.margin && x <= size_px - v.margin)
      canvas.line(x, v.margin, x, size_px - v.margin, kGrid);
  }
  for (int i = static_cast<int>(std::floor(v.max_y - metres));
       i <= static_cast<int>(std::ceil(v.max_y)); ++i) {
    const double y = v.px({0, i}).y();
    if (y >= v.margin && y <= size_px - v.margin)
      canvas.line(v.margin, y, size_px - v.margin, y, kGrid);
  }
  for (const auto& t : v.tables) {
    // Fill: scanline test against the convex hull (point-in-polygon by winding).
    if (t.hull.size() >= 3) {
      for (int y = v.margin; y < size_px - v.margin; ++y) {
        for (int x = v.margin; x < size_px - v.margin; ++x) {
          const Eigen::Vector2d p(v.min_x + (x - v.margin) / v.scale,
                                  v.max_y - (y - v.margin) / v.scale);
          bool inside = true;
          for (std::size_t i = 0; i < t.hull.size() && inside; ++i) {
            const Eigen::Vector2d a = t.hull[i], b = t.hull[(i + 1) % t.hull.size()];
            inside = (b - a).x() * (p - a).y() - (b - a).y() * (p - a).x() >= 0;  // CCW hull
          }
          if (inside) canvas.pixel(x, y, kTableFill);
        }
      }
    }
    for (std::size_t i = 0; i < t.hull.size(); ++i) {
      const auto a = v.px(t.hull[i]), b = v.px(t.hull[(i + 1) % t.hull.size()]);
      canvas.line(a.x(), a.y(), b.x(), b.y(), kBlack, 2);
    }
    const auto c = v.px(t.center);
    canvas.text(static_cast<int>(c.x()) - 6, static_cast<int>(c.y()) - 7, tableName(t.id), kBlack,
                2);
  }
  for (const auto& p : v.positions) {
    const auto c = v.px(p.position.xy.cast<double>());
    // Which way the robot would face there.
    canvas.line(c.x(), c.y(), c.x() + 22 * std::cos(p.position.yaw),
                c.y() - 22 * std::sin(p.position.yaw), kBlack, 2);
    drawPositionMarker(canvas, c.x(), c.y(), p.order, 9);
  }
  // Robot: a disc with a heading line.
  const auto r = v.px(v.robot);
  canvas.disc(r.x(), r.y(), 12, kRobot);
  canvas.line(r.x(), r.y(), r.x() + 24 * std::cos(v.robot_yaw), r.y() - 24 * std::sin(v.robot_yaw),
              kRobot, 3);
  canvas.text(static_cast<int>(r.x()) - 14, static_cast<int>(r.y()) + 16, "ROBOT", kRobot, 1);
  canvas.text(8, 8, title(v, tables), kBlack, 1);
  canvas.text(8, size_px - 14, "grid 1 m; x right, y up", kBlack, 1);
  return canvas.image();
}

std::string tableMapSvg(const io::TablesMessage& tables, int size_px) {
  const TopDown v = topDown(tables, size_px);
  std::ostringstream s;
  s.precision(2);
  s << std::fixed;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << size_px << "\" height=\"" << size_px
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"8\" y=\"16\">" << title(v, tables) << "</text>\n";
  for (const auto& t : v.tables) {
    s << "<polygon fill=\"rgb(150,215,150)\" stroke=\"black\" stroke-width=\"2\" points=\"";
    for (const auto& p : t.hull) {
      const auto q = v.px(p);
      s << q.x() << "," << q.y() << " ";
    }
    const auto c = v.px(t.center);
    s << "\"/>\n<text x=\"" << c.x() << "\" y=\"" << c.y()
      << "\" font-size=\"16\" text-anchor=\"middle\">T" << t.id << "</text>\n";
  }
  for (const auto& p : v.positions) {
    const auto c = v.px(p.position.xy.cast<double>());
    s << "<line x1=\"" << c.x() << "\" y1=\"" << c.y() << "\" x2=\""
      << c.x() + 22 * std::cos(p.position.yaw) << "\" y2=\""
      << c.y() - 22 * std::sin(p.position.yaw) << "\" stroke=\"black\" stroke-width=\"2\"/>\n";
    s << "<circle cx=\"" << c.x() << "\" cy=\"" << c.y() << "\" r=\"9\" stroke=\"black\" fill=\""
      << (p.order > 0 ? "rgb(40,200,60)" : "rgb(220,40,40)") << "\"><title>table " << p.table
      << (p.order > 0 ? ", visit " + std::to_string(p.order)
                      : ", unreachable: " + xmlEscape(p.position.reason))
      << "</title></circle>\n";
    s << "<text x=\"" << c.x() << "\" y=\"" << c.y() + 4 << "\" text-anchor=\"middle\" fill=\""
      << (p.order > 0 ? "black" : "white") << "\">" << (p.order > 0 ? std::to_string(p.order) : "x")
      << "</text>\n";
  }
  const auto r = v.px(v.robot);
  s << "<circle cx=\"" << r.x() << "\" cy=\"" << r.y() << "\" r=\"12\" fill=\"rgb(30,110,255)\"/>\n"
    << "<line x1=\"" << r.x() << "\" y1=\"" << r.y() << "\" x2=\""
    << r.x() + 24 * std::cos(v.robot_yaw) << "\" y2=\"" << r.y() - 24 * std::sin(v.robot_yaw)
    << "\" stroke=\"rgb(30,110,255)\" stroke-width=\"3\"/>\n"
    << "<text x=\"" << r.x() << "\" y=\"" << r.y() + 28
    << "\" text-anchor=\"middle\" fill=\"rgb(30,110,255)\">robot</text>\n"
    << "</svg>\n";
  return s.str();
}

}  // namespace findmug::clients
