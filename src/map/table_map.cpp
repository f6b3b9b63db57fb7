// table_map.cpp — tables in the map frame, merged across frames (see table_map.hpp).
//
// Association works on footprints rather than centres: a table seen from
// one end and later from the other gives two partial clusters whose centres
// can be a metre apart while their hulls overlap. The hull of the recent
// observations' hulls then grows to the whole top. Only the newest
// `max_observations` are kept so that odometry drift and a moved table
// cannot inflate a table forever.
#include "findmug/map/table_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <utility>

#include "findmug/common/error.hpp"

namespace findmug {

namespace {

float cross(const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return a.x() * b.y() - a.y() * b.x();
}

std::string formatNumber(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

// Distance from point p to segment ab.
float pointSegmentDistance(const Eigen::Vector2f& p, const Eigen::Vector2f& a,
                           const Eigen::Vector2f& b) {
  const Eigen::Vector2f ab = b - a;
  const float len2 = ab.squaredNorm();
  const float t = len2 > 0.0f ? std::clamp((p - a).dot(ab) / len2, 0.0f, 1.0f) : 0.0f;
  return (a + t * ab - p).norm();
}

bool insideConvex(const Eigen::Vector2f& p, const std::vector<Eigen::Vector2f>& polygon) {
  if (polygon.size() < 3) return false;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2f& a = polygon[i];
    const Eigen::Vector2f& b = polygon[(i + 1) % polygon.size()];
    if (cross(b - a, p - a) < 0.0f) return false;
  }
  return true;
}

// Principal axes, centre and half-extents of a convex polygon's area (the
// PCA of a uniformly filled top), written into `table`.
void describeFootprint(const std::vector<Eigen::Vector2f>& hull, TableCluster& table) {
  const Eigen::Vector2f origin = hull.front();  // shift for precision far from the map origin
  double area2 = 0.0, cx = 0.0, cy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d p = (hull[i] - origin).cast<double>();
    const Eigen::Vector2d q = (hull[(i + 1) % hull.size()] - origin).cast<double>();
    const double c = p.x() * q.y() - q.x() * p.y();
    area2 += c;
    cx += (p.x() + q.x()) * c;
    cy += (p.y() + q.y()) * c;
    sxx += (p.x() * p.x() + p.x() * q.x() + q.x() * q.x()) * c;
    syy += (p.y() * p.y() + p.y() * q.y() + q.y() * q.y()) * c;
    sxy += (p.x() * q.y() + 2.0 * p.x() * p.y() + 2.0 * q.x() * q.y() + q.x() * p.y()) * c;
  }
  Eigen::Vector2f major = Eigen::Vector2f::UnitX();
  Eigen::Vector2f centroid = origin;
  if (std::abs(area2) > 1e-12) {
    const double area = 0.5 * area2;
    const double mx = cx / (3.0 * area2), my = cy / (3.0 * area2);
    const double cov_xx = sxx / (12.0 * area) - mx * mx;
    const double cov_yy = syy / (12.0 * area) - my * my;
    const double cov_xy = sxy / (24.0 * area) - mx * my;
    const double angle = 0.5 * std::atan2(2.0 * cov_xy, cov_xx - cov_yy);
    major =
        Eigen::Vector2f(static_cast<float>(std::cos(angle)), static_cast<float>(std::sin(angle)));
    centroid = origin + Eigen::Vector2f(static_cast<float>(mx), static_cast<float>(my));
  }
  if (major.x() < 0.0f || (major.x() == 0.0f && major.y() < 0.0f)) major = -major;
  const Eigen::Vector2f minor(-major.y(), major.x());
  float lo_a = std::numeric_limits<float>::max(), hi_a = std::numeric_limits<float>::lowest();
  float lo_b = lo_a, hi_b = hi_a;
  for (const auto& p : hull) {
    const Eigen::Vector2f q = p - centroid;
    lo_a = std::min(lo_a, q.dot(major));
    hi_a = std::max(hi_a, q.dot(major));
    lo_b = std::min(lo_b, q.dot(minor));
    hi_b = std::max(hi_b, q.dot(minor));
  }
  table.major_axis = major;
  table.minor_axis = minor;
  table.extents = Eigen::Vector2f(0.5f * (hi_a - lo_a), 0.5f * (hi_b - lo_b));
  table.center = centroid + major * 0.5f * (hi_a + lo_a) + minor * 0.5f * (hi_b + lo_b);
  table.centroid.head<2>() = centroid;
}

[[noreturn]] void badMapSetting(const std::string& key, double value, const std::string& rule) {
  throw Error("table_map." + key + " = " + formatNumber(value) + ": " + rule);
}

}  // namespace

// ---------------------------------------------------------------------------
// Poses and polygons.

TableCluster transformTable(const TableCluster& table, const Pose2D& pose) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  const auto rotate = [&](const Eigen::Vector2f& v) {
    return Eigen::Vector2f(static_cast<float>(c * v.x() - s * v.y()),
                           static_cast<float>(s * v.x() + c * v.y()));
  };
  TableCluster out = table;
  out.centroid.head<2>() = transformPoint(pose, table.centroid.head<2>());
  out.major_axis = rotate(table.major_axis);
  out.minor_axis = rotate(table.minor_axis);
  out.center = transformPoint(pose, table.center);
  for (auto& p : out.hull) p = transformPoint(pose, p);
  for (auto& position : out.search_positions) {
    position.xy = transformPoint(pose, position.xy);
    position.yaw = static_cast<float>(wrapAngle(position.yaw + pose.yaw));
  }
  return out;
}

float polygonArea(const std::vector<Eigen::Vector2f>& polygon) {
  if (polygon.size() < 3) return 0.0f;
  double area2 = 0.0;
  const Eigen::Vector2f origin = polygon.front();
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
    area2 += cross(polygon[i] - origin, polygon[i + 1] - origin);
  }
  return static_cast<float>(0.5 * area2);
}

std::vector<Eigen::Vector2f> intersectConvex(const std::vector<Eigen::Vector2f>& a,
                                             const std::vector<Eigen::Vector2f>& b) {
  // Sutherland–Hodgman: clip `a` by each edge of `b` (both counter-clockwise).
  std::vector<Eigen::Vector2f> out = a;
  if (a.size() < 3 || b.size() < 3) return {};
  for (std::size_t i = 0; i < b.size() && !out.empty(); ++i) {
    const Eigen::Vector2f& e0 = b[i];
    const Eigen::Vector2f edge = b[(i + 1) % b.size()] - e0;
    std::vector<Eigen::Vector2f> in = std::move(out);
    out.clear();
    for (std::size_t k = 0; k < in.size(); ++k) {
      const Eigen::Vector2f& p = in[k];
      const Eigen::Vector2f& q = in[(k + 1) % in.size()];
      const float dp = cross(edge, p - e0), dq = cross(edge, q - e0);
      if (dp >= 0.0f) out.push_back(p);
      if ((dp >= 0.0f) != (dq >= 0.0f)) out.push_back(p + (q - p) * (dp / (dp - dq)));
    }
  }
  return out.size() >= 3 ? out : std::vector<Eigen::Vector2f>{};
}

float convexGap(const std::vector<Eigen::Vector2f>& a, const std::vector<Eigen::Vector2f>& b) {
  if (a.empty() || b.empty()) return std::numeric_limits<float>::infinity();
  if (!intersectConvex(a, b).empty() || insideConvex(a.front(), b) || insideConvex(b.front(), a)) {
    return 0.0f;
  }
  // Disjoint convex polygons: the closest pair involves a vertex of one.
  float best = std::numeric_limits<float>::infinity();
  for (int pass = 0; pass < 2; ++pass) {
    const auto& from = pass == 0 ? a : b;
    const auto& to = pass == 0 ? b : a;
    for (const auto& p : from) {
      for (std::size_t i = 0; i < to.size(); ++i) {
        best = std::min(best, pointSegmentDistance(p, to[i], to[(i + 1) % to.size()]));
      }
    }
  }
  return best;
}

// ---------------------------------------------------------------------------
// The map.

void validateTableMapConfig(const TableMapConfig& c) {
  if (c.confirm_sightings < 1)
    badMapSetting("confirm_sightings", c.confirm_sightings, "must be >= 1");
  if (c.forget_misses < 1) badMapSetting("forget_misses", c.forget_misses, "must be >= 1");
  if (!std::isfinite(c.tentative_timeout_s) || c.tentative_timeout_s <= 0.0) {
    badMapSetting("tentative_timeout_s", c.tentative_timeout_s, "must be a positive number");
  }
  if (!std::isfinite(c.match_gap_m) || c.match_gap_m < 0.0f) {
    badMapSetting("match_gap_m", c.match_gap_m, "must be a number >= 0");
  }
  if (!std::isfinite(c.match_height_m) || c.match_height_m < 0.0f) {
    badMapSetting("match_height_m", c.match_height_m, "must be a number >= 0");
  }
  if (!std::isfinite(c.view_half_angle_rad) || c.view_half_angle_rad <= 0.0f ||
      c.view_half_angle_rad > static_cast<float>(std::numbers::pi)) {
    badMapSetting("view_half_angle_rad", c.view_half_angle_rad, "must be in (0, pi]");
  }
  if (!std::isfinite(c.view_min_range_m) || c.view_min_range_m < 0.0f) {
    badMapSetting("view_min_range_m", c.view_min_range_m, "must be a number >= 0");
  }
  if (!std::isfinite(c.view_max_range_m) || c.view_max_range_m <= c.view_min_range_m) {
    badMapSetting(
        "view_max_range_m", c.view_max_range_m,
        "must be above table_map.view_min_range_m (" + formatNumber(c.view_min_range_m) + ")");
  }
  if (!std::isfinite(c.hidden_margin_m) || c.hidden_margin_m < 0.0f) {
    badMapSetting("hidden_margin_m", c.hidden_margin_m, "must be a number >= 0");
  }
  if (c.max_observations < 1) badMapSetting("max_observations", c.max_observations, "must be >= 1");
  if (!std::isfinite(c.position_match_m) || c.position_match_m < 0.0f) {
    badMapSetting("position_match_m", c.position_match_m, "must be a number >= 0");
  }
}

TableMap::TableMap(TableMapConfig map_config, TableConfig table_config)
    : map_config_(map_config), table_config_(table_config) {
  validateTableMapConfig(map_config_);
  validateTableConfig(table_config_);
}

void TableMap::clear() {
  tables_.clear();
  observations_.clear();
  // Ids are not reused even across a clear: a client may still hold old ones.
  last_utime_ = 0;
}

std::vector<TableCluster> TableMap::confirmedTables() const {
  std::vector<TableCluster> out;
  for (const auto& t : tables_) {
    if (t.confirmed) out.push_back(t.table);
  }
  return out;
}

bool TableMap::expectedInView(const TableCluster& table, const Pose2D& base_in_map) const {
  const Eigen::Vector2f in_base = transformPoint(inversePose(base_in_map), table.center);
  const float range = in_base.norm();
  const float bearing = std::atan2(in_base.y(), in_base.x());
  return range >= map_config_.view_min_range_m && range <= map_config_.view_max_range_m &&
         std::abs(bearing) <= map_config_.view_half_angle_rad;
}

void TableMap::rebuild(std::size_t index) {
  const auto& observations = observations_[index];
  TableCluster& table = tables_[index].table;
  std::vector<Eigen::Vector2f> corners;
  double top_sum = 0.0, z_sum = 0.0, confidence_sum = 0.0;
  for (const auto& [obs_utime, obs] : observations) {
    corners.insert(corners.end(), obs.hull.begin(), obs.hull.end());
    top_sum += obs.top_height;
    z_sum += obs.centroid.z();
    confidence_sum += obs.mean_confidence;
  }
  const double n = static_cast<double>(observations.size());
  table.hull = convexHull2d(std::move(corners));
  table.top_height = static_cast<float>(top_sum / n);
  table.centroid.z() = static_cast<float>(z_sum / n);
  table.mean_confidence = static_cast<float>(confidence_sum / n);
  table.point_count = observations.back().table.point_count;
  if (table.hull.size() >= 3) {
    describeFootprint(table.hull, table);
  } else {
    // Observations from findTables always have an area; keep the newest box otherwise.
    const TableCluster& newest = observations.back().table;
    table.major_axis = newest.major_axis;
    table.minor_axis = newest.minor_axis;
    table.extents = newest.extents;
    table.center = newest.center;
    table.centroid.head<2>() = newest.centroid.head<2>();
  }
  table.search_positions = computeSearchPositions(table, table_config_);
  for (auto& position : table.search_positions) {
    position.reachable = false;
    position.reason = "not observed yet";
    // Newest observation first: the latest evidence about a spot wins.
    for (auto obs = observations.rbegin(); obs != observations.rend(); ++obs) {
      const SearchPosition* nearest = nullptr;
      float nearest_distance = map_config_.position_match_m;
      for (const auto& seen : obs->table.search_positions) {
        const float distance = (seen.xy - position.xy).norm();
        if (distance <= nearest_distance) {
          nearest_distance = distance;
          nearest = &seen;
        }
      }
      if (nearest != nullptr) {
        position.reachable = nearest->reachable;
        position.reason = nearest->reason;
        break;
      }
    }
  }
}

bool TableMap::topInSight(const TableCluster& table, const DepthView& view) const {
  // The box centre and points 60 % of the way from it to each hull corner: inside the
  // top, clear of its edge.
  const Eigen::Vector2f centre = table.center;
  int shown = 0, hidden = 0;
  const auto sample = [&](const Eigen::Vector2f& xy) {
    const Eigen::Vector3d p(xy.x(), xy.y(), table.top_height);
    const DepthView::Point seen = view.show(p, map_config_.hidden_margin_m, 0);
    shown += seen == DepthView::Point::Shown;
    hidden += seen == DepthView::Point::Hidden;
  };
  sample(centre);
  for (const Eigen::Vector2f& corner : table.hull) sample(centre + 0.6f * (corner - centre));
  return shown > 0 && shown >= hidden;
}

TableMapUpdate TableMap::update(const std::vector<TableCluster>& tables_base,
                                const Pose2D& base_in_map, std::uint64_t utime,
                                const DepthView* view) {
  if (!std::isfinite(base_in_map.x) || !std::isfinite(base_in_map.y) ||
      !std::isfinite(base_in_map.yaw)) {
    throw Error("TableMap::update: robot pose (" + formatNumber(base_in_map.x) + ", " +
                formatNumber(base_in_map.y) + ", " + formatNumber(base_in_map.yaw) +
                ") is not finite");
  }
  if (utime < last_utime_) {
    throw Error("TableMap::update: utime " + std::to_string(utime) + " is older than the last (" +
                std::to_string(last_utime_) + ")");
  }
  last_utime_ = utime;
  TableMapUpdate result;
  std::vector<bool> seen(tables_.size(), false);

  // Associate each observation with the mapped table whose footprint it
  // overlaps most (or, failing overlap, comes closest to), heights agreeing.
  for (const TableCluster& observed_base : tables_base) {
    TableCluster observed = transformTable(observed_base, base_in_map);
    int best = -1;
    float best_overlap = -1.0f, best_gap = std::numeric_limits<float>::infinity();
    for (std::size_t j = 0; j < tables_.size(); ++j) {
      const TableCluster& mapped = tables_[j].table;
      if (std::abs(mapped.top_height - observed.top_height) > map_config_.match_height_m) continue;
      const float gap = convexGap(mapped.hull, observed.hull);
      if (gap > map_config_.match_gap_m) continue;
      const float overlap = polygonArea(intersectConvex(mapped.hull, observed.hull));
      if (overlap > best_overlap || (overlap == best_overlap && gap < best_gap)) {
        best = static_cast<int>(j);
        best_overlap = overlap;
        best_gap = gap;
      }
    }
    if (best < 0) {
      MappedTable created;
      created.table.id = next_id_++;
      created.first_seen_utime = utime;
      tables_.push_back(std::move(created));
      observations_.emplace_back();
      seen.push_back(false);
      best = static_cast<int>(tables_.size()) - 1;
      result.created.push_back(tables_[best].table.id);
    }
    auto& kept = observations_[best];
    kept.push_back({utime, std::move(observed)});
    while (static_cast<int>(kept.size()) > map_config_.max_observations) kept.pop_front();
    seen[best] = true;
    rebuild(static_cast<std::size_t>(best));
    result.assigned_ids.push_back(tables_[best].table.id);
  }

  // Sightings, misses, confirmation, forgetting.
  std::vector<bool> remove(tables_.size(), false);
  for (std::size_t j = 0; j < tables_.size(); ++j) {
    MappedTable& t = tables_[j];
    if (seen[j]) {
      ++t.sightings;
      t.misses = 0;
      t.last_seen_utime = utime;
      if (!t.confirmed && t.sightings >= map_config_.confirm_sightings) {
        t.confirmed = true;
        result.confirmed.push_back(t.table.id);
      }
      continue;
    }
    if (expectedInView(t.table, base_in_map) && (view == nullptr || topInSight(t.table, *view)))
      ++t.misses;
    if (t.misses >= map_config_.forget_misses) {
      remove[j] = true;
      result.diagnostics.push_back("table " + std::to_string(t.table.id) +
                                   " forgotten: not seen where expected in " +
                                   std::to_string(t.misses) + " consecutive frames");
    } else if (!t.confirmed && static_cast<double>(utime - t.first_seen_utime) * 1e-6 >
                                   map_config_.tentative_timeout_s) {
      remove[j] = true;
      result.diagnostics.push_back("tentative table " + std::to_string(t.table.id) +
                                   " dropped: not confirmed within " +
                                   formatNumber(map_config_.tentative_timeout_s) + " s");
    }
  }

  // Tables whose footprints have grown into each other are one table: the
  // older (lower) id absorbs the other's observations.
  for (std::size_t j = 0; j < tables_.size(); ++j) {
    if (remove[j]) continue;
    for (std::size_t k = j + 1; k < tables_.size(); ++k) {
      if (remove[k]) continue;
      const TableCluster& a = tables_[j].table;
      const TableCluster& b = tables_[k].table;
      if (std::abs(a.top_height - b.top_height) > map_config_.match_height_m) continue;
      const float overlap = polygonArea(intersectConvex(a.hull, b.hull));
      const float smaller = std::min(polygonArea(a.hull), polygonArea(b.hull));
      if (!(overlap > 0.5f * smaller)) continue;
      MappedTable& keep = tables_[j];
      const MappedTable& gone = tables_[k];
      result.diagnostics.push_back("table " + std::to_string(gone.table.id) +
                                   " merged into table " + std::to_string(keep.table.id) +
                                   " (footprints overlap)");
      for (int& id : result.assigned_ids) {
        if (id == gone.table.id) id = keep.table.id;
      }
      keep.sightings = std::max(keep.sightings, gone.sightings);
      keep.misses = std::min(keep.misses, gone.misses);
      keep.first_seen_utime = std::min(keep.first_seen_utime, gone.first_seen_utime);
      keep.last_seen_utime = std::max(keep.last_seen_utime, gone.last_seen_utime);
      if (gone.confirmed && !keep.confirmed) {
        keep.confirmed = true;
        result.confirmed.push_back(keep.table.id);
      }
      // Oldest first, whichever table they came from; keep the newest.
      auto& kept = observations_[j];
      kept.insert(kept.end(), observations_[k].begin(), observations_[k].end());
      std::stable_sort(kept.begin(), kept.end(), [](const Observation& x, const Observation& y) {
        return x.utime < y.utime;
      });
      while (static_cast<int>(kept.size()) > map_config_.max_observations) kept.pop_front();
      rebuild(j);
      remove[k] = true;
    }
  }

  std::vector<MappedTable> tables;
  std::vector<std::deque<Observation>> observations;
  for (std::size_t j = 0; j < tables_.size(); ++j) {
    if (remove[j]) {
      result.forgotten.push_back(tables_[j].table.id);
      continue;
    }
    tables.push_back(std::move(tables_[j]));
    observations.push_back(std::move(observations_[j]));
  }
  tables_ = std::move(tables);
  observations_ = std::move(observations);
  return result;
}

const SettingsTable<TableMapConfig>& tableMapSettings() {
  using M = TableMapConfig;
  static const SettingsTable<M> table = [] {
    SettingsTable<M> t("table_map");
    t.add(integerSetting<M, int>(
        "table_map.confirm_sightings", [](M& m) -> int& { return m.confirm_sightings; }, 1, 1000,
        "sightings (updates with a match) to confirm a table"));
    t.add(integerSetting<M, int>(
        "table_map.forget_misses", [](M& m) -> int& { return m.forget_misses; }, 1, 1000,
        "consecutive expected-but-unseen updates to forget a table"));
    t.add(numberSetting<M, double>(
        "table_map.tentative_timeout_s", [](M& m) -> double& { return m.tentative_timeout_s; },
        0, 86400, "unconfirmed tables older than this are dropped"));
    t.add(numberSetting<M, float>(
        "table_map.match_gap_m", [](M& m) -> float& { return m.match_gap_m; }, 0, 5,
        "footprints this close may be one table"));
    t.add(numberSetting<M, float>(
        "table_map.match_height_m", [](M& m) -> float& { return m.match_height_m; }, 0, 2,
        "... when their top heights differ by at most this"));
    t.add(numberSetting<M, float>(
        "table_map.view_half_angle_rad", [](M& m) -> float& { return m.view_half_angle_rad; },
        0, 3.14159, "half opening angle of the camera's view on the floor"));
    t.add(numberSetting<M, float>(
        "table_map.view_min_range_m", [](M& m) -> float& { return m.view_min_range_m; }, 0, 100,
        "near end of the range where a mapped table is expected in view"));
    t.add(numberSetting<M, float>(
        "table_map.view_max_range_m", [](M& m) -> float& { return m.view_max_range_m; }, 0, 100,
        "far end of that range"));
    t.add(numberSetting<M, float>(
        "table_map.hidden_margin_m", [](M& m) -> float& { return m.hidden_margin_m; }, 0, 5,
        "depth this much nearer than a mapped top hides it: not seen there is no miss"));
    t.add(integerSetting<M, int>(
        "table_map.max_observations", [](M& m) -> int& { return m.max_observations; }, 1, 1000,
        "newest observations kept per table"));
    t.add(numberSetting<M, float>(
        "table_map.position_match_m", [](M& m) -> float& { return m.position_match_m; }, 0, 5,
        "observed search position this near a recomputed one lends its verdict"));
    return t;
  }();
  return table;
}

}  // namespace findmug
