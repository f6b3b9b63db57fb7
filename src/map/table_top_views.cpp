// table_top_views.cpp — TableTopViews: the table-top cells views have shown (see the header).
#include "findmug/map/table_top_views.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "findmug/common/error.hpp"
#include "findmug/map/depth_view.hpp"

namespace findmug {

namespace {

// Inside a convex counter-clockwise polygon (on its edge counts as inside).
bool insideConvex(const std::vector<Eigen::Vector2f>& hull, float x, float y) {
  const std::size_t n = hull.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2f& a = hull[i];
    const Eigen::Vector2f& b = hull[(i + 1) % n];
    if ((b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x()) < 0.0f) return false;
  }
  return true;
}

}  // namespace

void validateTableTopViewsConfig(const TableTopViewsConfig& config) {
  auto positive = [](float v, const char* name) {
    if (!(v > 0.0f) || !std::isfinite(v))
      throw Error(std::string("table top views: ") + name + " must be positive, got " +
                  std::to_string(v));
  };
  positive(config.range_m, "range_m");
  positive(config.cell_m, "cell_m");
  positive(config.occlusion_m, "occlusion_m");
  if (config.cell_m < 0.01f)
    throw Error("table top views: cell_m must be at least 0.01 m, got " +
                std::to_string(config.cell_m));
  if (config.border_px < 0)
    throw Error("table top views: border_px must not be negative, got " +
                std::to_string(config.border_px));
}

TableTopViews::TableTopViews(TableTopViewsConfig config) : config_(config) {
  validateTableTopViewsConfig(config_);
}

std::uint64_t TableTopViews::key(int ix, int iy) const {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32) |
         static_cast<std::uint32_t>(iy);
}

template <class F>
void TableTopViews::forEachTopCell(const TableCluster& table, F&& f) const {
  if (table.hull.size() < 3) return;
  float x0 = table.hull[0].x(), x1 = x0, y0 = table.hull[0].y(), y1 = y0;
  for (const Eigen::Vector2f& p : table.hull) {
    x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
    y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
  }
  const float c = config_.cell_m;
  for (int iy = static_cast<int>(std::floor(y0 / c)); iy <= static_cast<int>(std::floor(y1 / c));
       ++iy) {
    for (int ix = static_cast<int>(std::floor(x0 / c));
         ix <= static_cast<int>(std::floor(x1 / c)); ++ix) {
      const float x = (static_cast<float>(ix) + 0.5f) * c, y = (static_cast<float>(iy) + 0.5f) * c;
      if (insideConvex(table.hull, x, y)) f(ix, iy, x, y);
    }
  }
}

int TableTopViews::observe(const std::vector<TableCluster>& map_tables, const RgbdFrame& frame,
                           const Eigen::Isometry3d& camera_in_map) {
  const DepthView view(frame, camera_in_map);
  const Eigen::Vector3d& camera = view.cameraPosition();
  const double range2 = static_cast<double>(config_.range_m) * config_.range_m;
  int added = 0;
  for (const TableCluster& table : map_tables) {
    const double z = table.top_height;
    // A top wholly out of range is skipped before its cells are walked.
    if (table.hull.size() >= 3) {
      double nearest2 = std::numeric_limits<double>::max();
      const Eigen::Vector2d c(camera.x(), camera.y());
      for (const Eigen::Vector2f& p : table.hull)
        nearest2 = std::min(nearest2, (p.cast<double>() - c).squaredNorm());
      const double dz = z - camera.z();
      const Eigen::Vector2d centre = table.center.cast<double>();
      if (std::min(nearest2, (centre - c).squaredNorm()) + dz * dz > range2 * 4.0) continue;
    }
    forEachTopCell(table, [&](int ix, int iy, float x, float y) {
      const Eigen::Vector3d p(x, y, z);
      if ((p - camera).squaredNorm() > range2) return;
      if (view.show(p, config_.occlusion_m, config_.border_px) != DepthView::Point::Shown) return;
      if (seen_.insert(key(ix, iy)).second) ++added;
    });
  }
  return added;
}

double TableTopViews::seenShare(const TableCluster& table) const {
  int cells = 0, seen = 0;
  forEachTopCell(table, [&](int ix, int iy, float, float) {
    ++cells;
    if (seen_.count(key(ix, iy)) != 0) ++seen;
  });
  return cells == 0 ? 0.0 : static_cast<double>(seen) / cells;
}

}  // namespace findmug
