// table_objects.cpp — findTableObjects: the object candidates standing on the
// frame's table tops (steps in table_objects.hpp), their colour histograms and
// the relabelling of their table-labelled pixels.
//
// Cost: one pass over the frame rejects almost every pixel with two loads and
// a few compares (label, height band of any table), and only the pixels above
// a table's bounding box meet the point-in-polygon test; the clustering and
// the per-candidate work then see a few thousand points. The Euclidean
// clustering is the tables' own (tables_internal.hpp), with the image grid as
// its shortcut.
#include "findmug/objects/table_objects.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "common/scratch.hpp"
#include "common/union_find.hpp"
#include "findmug/common/error.hpp"
#include "findmug/labels/labels.hpp"
#include "objects/table_objects_internal.hpp"
#include "tables/tables_internal.hpp"

namespace findmug {

namespace {

using objects_detail::clusterSampled;
using objects_detail::colourBin;
using objects_detail::normaliseColourCounts;
using tables_detail::fmt;

constexpr auto kFloorLabel = static_cast<std::uint8_t>(Label::Floor);
constexpr auto kWallLabel = static_cast<std::uint8_t>(Label::Wall);
constexpr auto kCeilingLabel = static_cast<std::uint8_t>(Label::Ceiling);
constexpr auto kTableLabel = static_cast<std::uint8_t>(Label::Table);
constexpr auto kObjectLabel = static_cast<std::uint8_t>(Label::Object);
// Within this of the grown outline a candidate may go on past it (kTruncatedOutline).
constexpr float kOutlineFlagM = 0.01f;
// Pixels this close to the image edge: the object may go on outside the view.
constexpr int kBorderPx = 2;
// Spare pixel lists kept per thread when a frame has fewer candidates than the last.
constexpr std::size_t kMaxSparePixelLists = 64;

[[noreturn]] void badSetting(const std::string& key, double value, const std::string& rule) {
  throw Error("table_objects." + key + " = " + fmt(value, 6) + ": " + rule);
}

void checkRange(const std::string& key, double value, double lo, double hi) {
  if (!(value >= lo && value <= hi)) {
    badSetting(key, value, "must be in [" + fmt(lo, 6) + ", " + fmt(hi, 6) + "]");
  }
}

// One edge of a table's hull as a half-plane: n . p - c is the signed
// distance of p from the edge's line, positive inside (n the inward unit normal).
struct HalfPlane {
  float nx = 0, ny = 0, c = 0;
  float distance(float x, float y) const { return nx * x + ny * y - c; }
};

// What the pixel pass needs of one table: its height band, the bounding box of
// its grown hull and the hull's edges (edges[first .. first + count)).
struct TableRegion {
  int table = 0;
  float top = 0, z_lo = 0, z_hi = 0;
  float x_lo = 0, x_hi = 0, y_lo = 0, y_hi = 0;
  int first = 0, count = 0;
};

// One candidate's colour sums, bin counts and truncation findings.
struct ObjectSums {
  double r = 0, g = 0, b = 0;
  std::array<int, kObjectColourBins> bins{};
  bool border = false;
  // The object's box on the floor.
  float x_lo = std::numeric_limits<float>::infinity(), x_hi = -x_lo;
  float y_lo = std::numeric_limits<float>::infinity(), y_hi = -y_lo;
};

// Per-thread working memory (scratch.hpp).
struct Scratch {
  std::vector<TableRegion> regions;
  std::vector<HalfPlane> edges;
  // Per region: the points above its top in pixel order, their pixels, and
  // their cluster indices.
  std::vector<std::vector<Eigen::Vector3f>> points;
  std::vector<std::vector<int>> pixels;
  std::vector<std::vector<float>> heights;  // above the local top (see localTops)
  std::vector<double> cell_sum;
  std::vector<int> cell_count;
  std::vector<float> cell_top;
  std::vector<std::vector<int>> cluster_of;
  std::vector<int> object_of_cluster, cluster_of_object;
  std::vector<ObjectSums> sums;
  // splitByLabel's: the split cluster's point indices, one label's points.
  std::vector<int> split_index, part_index, part_pixels, part_of;
  std::vector<Eigen::Vector3f> part_points;
  std::vector<std::vector<int>> spare_pixels;
  objects_detail::SampledClusteringScratch sampled;  // clusterSampled's
};

// The smallest signed distance of (x, y) to the region's edges: >= 0 inside the hull.
float minEdgeDistance(const HalfPlane* edges, int count, float x, float y) {
  float d = std::numeric_limits<float>::infinity();
  for (int k = 0; k < count; ++k) d = std::min(d, edges[k].distance(x, y));
  return d;
}

// Whether (x, y) is inside the hull grown by `margin` (every edge's distance >= -margin).
bool insideGrown(const HalfPlane* edges, int count, float x, float y, float margin) {
  for (int k = 0; k < count; ++k) {
    if (edges[k].distance(x, y) < -margin) return false;
  }
  return true;
}

// The regions of the tables whose hull is a polygon within the plausible
// range; the others are reported and left out.
void buildRegions(const std::vector<TableCluster>& tables, const TableObjectConfig& config,
                  Scratch& s, std::vector<std::string>& diagnostics) {
  s.regions.clear();
  s.edges.clear();
  const float margin = config.outline_margin_m;
  for (std::size_t t = 0; t < tables.size(); ++t) {
    const TableCluster& table = tables[t];
    // Any order or duplicates in: the hull's edges must turn left.
    const std::vector<Eigen::Vector2f> hull = convexHull2d(table.hull);
    Eigen::AlignedBox2f box;
    for (const auto& p : hull) box.extend(p);
    if (hull.size() < 3 || !std::isfinite(table.top_height) || box.isEmpty() ||
        box.min().cwiseAbs().maxCoeff() > tables_detail::kMaxPlausibleRangeM - 1 ||
        box.max().cwiseAbs().maxCoeff() > tables_detail::kMaxPlausibleRangeM - 1) {
      diagnostics.push_back("table " + std::to_string(t) + ": no usable top outline (" +
                            std::to_string(hull.size()) + " hull points): no objects looked for");
      continue;
    }
    TableRegion r;
    r.table = static_cast<int>(t);
    r.top = table.top_height;
    // With local tops the band is widened by how far a local top may lie
    // from the table's (the top's own points are collected too, for localTops).
    const float slack = config.top_cell_m > 0 ? config.max_base_height_m : 0.0f;
    r.z_lo = table.top_height + (slack > 0 ? -slack : config.min_height_m);
    r.z_hi = table.top_height + slack + config.max_height_m;
    r.x_lo = box.min().x() - margin;
    r.x_hi = box.max().x() + margin;
    r.y_lo = box.min().y() - margin;
    r.y_hi = box.max().y() + margin;
    r.first = static_cast<int>(s.edges.size());
    for (std::size_t k = 0; k < hull.size(); ++k) {
      const Eigen::Vector2f a = hull[k], b = hull[(k + 1) % hull.size()];
      const Eigen::Vector2f e = b - a;
      const float length = e.norm();
      if (!(length > 0)) continue;
      HalfPlane h;
      h.nx = -e.y() / length;  // counter-clockwise: the inside is on the left
      h.ny = e.x() / length;
      h.c = h.nx * a.x() + h.ny * a.y();
      s.edges.push_back(h);
    }
    r.count = static_cast<int>(s.edges.size()) - r.first;
    s.regions.push_back(r);
  }
}

// Step 1: the points above the regions' tops, each to the first region that
// holds it, appended in pixel order. Returns how many.
int collectPointsAboveTops(const OrganizedCloud& cloud, const LabelImage& labels, float margin,
                           Scratch& s) {
  const std::size_t n_regions = s.regions.size();
  s.points.resize(n_regions);
  s.pixels.resize(n_regions);
  s.cluster_of.resize(n_regions);
  s.heights.resize(n_regions);
  float z_lo = std::numeric_limits<float>::infinity(), z_hi = -z_lo;
  for (std::size_t r = 0; r < n_regions; ++r) {
    s.points[r].clear();
    s.pixels[r].clear();
    z_lo = std::min(z_lo, s.regions[r].z_lo);
    z_hi = std::max(z_hi, s.regions[r].z_hi);
  }
  const Eigen::Vector3f* points = cloud.points.data();
  const std::uint8_t* label = labels.labels.data();
  const int n = static_cast<int>(cloud.points.size());
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    const float z = points[i].z();
    // NaN fails both compares: invalid pixels leave here.
    if (!(z >= z_lo && z <= z_hi)) continue;
    const std::uint8_t l = label[i];
    if (l == kFloorLabel || l == kWallLabel || l == kCeilingLabel) continue;
    const float x = points[i].x(), y = points[i].y();
    for (std::size_t r = 0; r < n_regions; ++r) {
      const TableRegion& g = s.regions[r];
      // The bounding box's compares are false for NaN x, y too.
      if (!(z >= g.z_lo && z <= g.z_hi && x >= g.x_lo && x <= g.x_hi && y >= g.y_lo &&
            y <= g.y_hi)) {
        continue;
      }
      if (!insideGrown(s.edges.data() + g.first, g.count, x, y, margin)) continue;
      s.points[r].push_back(points[i]);
      s.pixels[r].push_back(i);
      ++kept;
      break;
    }
  }
  return kept;
}

// A cluster's sums over its points (one pass), then its footprint.
struct ClusterStats {
  int count = 0;
  int first_pixel = 0;
  double sx = 0, sy = 0, sz = 0;     // sums of coordinates
  double sxx = 0, sxy = 0, syy = 0;  // of products, for the footprint's covariance
  float h_min = std::numeric_limits<float>::infinity();  // heights above the local top
  float h_max = -std::numeric_limits<float>::infinity();
  // Filled for clusters big enough: footprint axis and box along it.
  Eigen::Vector2f axis = Eigen::Vector2f::UnitX();
  float u_lo = std::numeric_limits<float>::infinity(), u_hi = -u_lo;
  float v_lo = std::numeric_limits<float>::infinity(), v_hi = -v_lo;
};

void addPoint(ClusterStats& c, const Eigen::Vector3f& p, int pixel, float height) {
  if (c.count == 0) c.first_pixel = pixel;
  ++c.count;
  const double x = p.x(), y = p.y();
  c.sx += x;
  c.sy += y;
  c.sz += p.z();
  c.sxx += x * x;
  c.sxy += x * y;
  c.syy += y * y;
  c.h_min = std::min(c.h_min, height);
  c.h_max = std::max(c.h_max, height);
}

void sumClusters(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& pixels,
                 const std::vector<float>& heights, const std::vector<int>& cluster_of,
                 std::vector<ClusterStats>& stats) {
  for (std::size_t k = 0; k < points.size(); ++k) {
    addPoint(stats[static_cast<std::size_t>(cluster_of[k])], points[k], pixels[k], heights[k]);
  }
}

// The footprint's box along the cluster's axis (u) and the axis turned +90° (v).
void extendBox(ClusterStats& s, const Eigen::Vector3f& p) {
  const float u = s.axis.x() * p.x() + s.axis.y() * p.y();
  const float v = -s.axis.y() * p.x() + s.axis.x() * p.y();
  s.u_lo = std::min(s.u_lo, u);
  s.u_hi = std::max(s.u_hi, u);
  s.v_lo = std::min(s.v_lo, v);
  s.v_hi = std::max(s.v_hi, v);
}

// The footprint's first principal axis (x >= 0, so that it is one direction
// whatever the points' order) from the sums.
Eigen::Vector2f principalAxis(const ClusterStats& c) {
  const double n = c.count;
  const double mx = c.sx / n, my = c.sy / n;
  const double cxx = c.sxx / n - mx * mx, cxy = c.sxy / n - mx * my, cyy = c.syy / n - my * my;
  const double angle = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);  // in [-pi/2, pi/2]
  Eigen::Vector2f axis(static_cast<float>(std::cos(angle)), static_cast<float>(std::sin(angle)));
  if (axis.x() < 0 || (axis.x() == 0 && axis.y() < 0)) axis = -axis;
  return axis;
}

// Half-lengths of the footprint's box along the axis and the axis turned +90°.
void footprintBoxes(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& cluster_of,
                    const std::vector<int>& big, std::vector<ClusterStats>& stats) {
  for (std::size_t k = 0; k < points.size(); ++k) {
    const int c = cluster_of[k];
    if (!big[static_cast<std::size_t>(c)]) continue;
    extendBox(stats[static_cast<std::size_t>(c)], points[k]);
  }
}

// A candidate before it is written out: where its cluster is and how it sorts.
struct Candidate {
  int region = 0;   // index into Scratch::regions
  int cluster = 0;  // within the region
  int table = 0;
  int count = 0;
  int first_pixel = 0;
};

// A pixel list for a new candidate: the one the object held, else a spare one.
void takePixelBuffer(TableObject& object, Scratch& s) {
  if (object.pixels.capacity() == 0 && !s.spare_pixels.empty()) {
    object.pixels = std::move(s.spare_pixels.back());
    s.spare_pixels.pop_back();
  }
  object.pixels.clear();
}

// kTruncatedDepthHole: of the candidate's edge pixels (a 4-neighbour in the
// image but not in the candidate), a quarter or more touch a pixel without a
// point. The pixels are ascending, so the neighbours above and below are
// looked up with cursors that only move forward: O(n), no search.
bool bordersDepthHoles(const std::vector<int>& pixels, const OrganizedCloud& cloud) {
  const int w = cloud.width, h = cloud.height;
  const int n = static_cast<int>(pixels.size());
  int edge = 0, hole = 0;
  int up = 0, down = 0;  // first pixels >= p - w and >= p + w
  for (int k = 0; k < n; ++k) {
    const int p = pixels[static_cast<std::size_t>(k)];
    const int x = p % w, y = p / w;
    while (up < n && pixels[static_cast<std::size_t>(up)] < p - w) ++up;
    while (down < n && pixels[static_cast<std::size_t>(down)] < p + w) ++down;
    const bool has_left = k > 0 && pixels[static_cast<std::size_t>(k - 1)] == p - 1;
    const bool has_right = k + 1 < n && pixels[static_cast<std::size_t>(k + 1)] == p + 1;
    const bool has_up = up < n && pixels[static_cast<std::size_t>(up)] == p - w;
    const bool has_down = down < n && pixels[static_cast<std::size_t>(down)] == p + w;
    bool is_edge = false, at_hole = false;
    auto look = [&](bool inside_image, bool in_candidate, int q) {
      if (!inside_image || in_candidate) return;
      is_edge = true;
      at_hole |= !cloud.valid(static_cast<std::size_t>(q));
    };
    look(x > 0, has_left, p - 1);
    look(x + 1 < w, has_right, p + 1);
    look(y > 0, has_up, p - w);
    look(y + 1 < h, has_down, p + w);
    edge += is_edge;
    hole += at_hole;
  }
  return edge > 0 && 4 * hole >= edge;
}

// kTruncatedOutline: whether a point of the object lies within kOutlineFlagM
// of the grown outline. The points inside a convex region form a convex set,
// so when the four corners of the object's box on the floor are all further
// inside, every point is and none needs a look.
bool nearOutline(const HalfPlane* edges, int count, float margin, const ObjectSums& a,
                 const std::vector<Eigen::Vector3f>& points, const std::vector<int>& cluster_of,
                 int cluster) {
  const float limit = -margin + kOutlineFlagM;
  auto far_inside = [&](float x, float y) { return minEdgeDistance(edges, count, x, y) > limit; };
  if (far_inside(a.x_lo, a.y_lo) && far_inside(a.x_hi, a.y_lo) && far_inside(a.x_lo, a.y_hi) &&
      far_inside(a.x_hi, a.y_hi)) {
    return false;
  }
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (cluster_of[k] == cluster && !far_inside(points[k].x(), points[k].y())) return true;
  }
  return false;
}

// Step 4 for one region: every candidate's fields from its points.
void describeCandidates(const OrganizedCloud& cloud, const TableRegion& region,
                        const HalfPlane* edges, float margin,
                        const std::vector<Eigen::Vector3f>& points, const std::vector<int>& pixels,
                        const std::vector<int>& cluster_of,
                        const std::vector<int>& object_of_cluster,
                        const std::vector<ClusterStats>& stats,
                        const std::vector<int>& cluster_of_object, std::vector<ObjectSums>& acc,
                        TableObjectDetection& out, int first_object) {
  const bool has_colour = cloud.colors.size() == cloud.points.size();
  const int w = cloud.width, h = cloud.height;
  const int n_objects = static_cast<int>(cluster_of_object.size());
  acc.assign(static_cast<std::size_t>(n_objects), ObjectSums{});
  for (std::size_t k = 0; k < points.size(); ++k) {
    const int o = object_of_cluster[static_cast<std::size_t>(cluster_of[k])];
    if (o < 0) continue;
    TableObject& object = out.objects[static_cast<std::size_t>(first_object + o)];
    ObjectSums& a = acc[static_cast<std::size_t>(o)];
    const int p = pixels[k];
    object.pixels.push_back(p);
    const int x = p % w, y = p / w;
    a.border |= x < kBorderPx || y < kBorderPx || x >= w - kBorderPx || y >= h - kBorderPx;
    a.x_lo = std::min(a.x_lo, points[k].x());
    a.x_hi = std::max(a.x_hi, points[k].x());
    a.y_lo = std::min(a.y_lo, points[k].y());
    a.y_hi = std::max(a.y_hi, points[k].y());
    if (has_colour) {
      const Rgb8& c = cloud.colors[static_cast<std::size_t>(p)];
      a.r += c.r;
      a.g += c.g;
      a.b += c.b;
      ++a.bins[static_cast<std::size_t>(colourBin(c))];
    }
  }
  for (int o = 0; o < n_objects; ++o) {
    const ClusterStats& c =
        stats[static_cast<std::size_t>(cluster_of_object[static_cast<std::size_t>(o)])];
    const ObjectSums& a = acc[static_cast<std::size_t>(o)];
    TableObject& object = out.objects[static_cast<std::size_t>(first_object + o)];
    const double n = c.count;
    object.table = region.table;
    object.centroid = Eigen::Vector3f(static_cast<float>(c.sx / n), static_cast<float>(c.sy / n),
                                      static_cast<float>(c.sz / n));
    object.height_above_top = c.h_max;
    object.major_axis = c.axis;
    object.extents = Eigen::Vector2f(0.5f * (c.u_hi - c.u_lo), 0.5f * (c.v_hi - c.v_lo));
    const float u = 0.5f * (c.u_lo + c.u_hi), v = 0.5f * (c.v_lo + c.v_hi);
    object.center =
        Eigen::Vector2f(c.axis.x() * u - c.axis.y() * v, c.axis.y() * u + c.axis.x() * v);
    object.point_count = c.count;
    object.mean_rgb =
        has_colour ? Eigen::Vector3f(static_cast<float>(a.r / n), static_cast<float>(a.g / n),
                                     static_cast<float>(a.b / n))
                   : Eigen::Vector3f::Zero();
    normaliseColourCounts(a.bins, has_colour ? c.count : 0, object.colour_histogram);
    object.truncation = static_cast<std::uint8_t>(
        (nearOutline(edges, region.count, margin, a, points, cluster_of,
                     cluster_of_object[static_cast<std::size_t>(o)])
             ? kTruncatedOutline
             : 0) |
        (a.border ? kTruncatedBorder : 0) |
        (bordersDepthHoles(object.pixels, cloud) ? kTruncatedDepthHole : 0));
  }
}

// Step 3's reason a cluster does not stand on the top, or empty.
std::string whyNotStanding(const ClusterStats& c, const TableRegion& region, const HalfPlane* edges,
                           const TableObjectConfig& config) {
  const float base = c.h_min;
  if (base > config.max_base_height_m) {
    return "base " + fmt(base) + " m above the top (table_objects.max_base_height_m " +
           fmt(config.max_base_height_m) + ")";
  }
  const auto cx = static_cast<float>(c.sx / c.count), cy = static_cast<float>(c.sy / c.count);
  if (minEdgeDistance(edges, region.count, cx, cy) < 0) {
    return "footprint centroid outside the top";
  }
  const float longer = std::max(c.u_hi - c.u_lo, c.v_hi - c.v_lo);
  if (longer > config.max_extent_m) {
    return "footprint " + fmt(longer) + " m long (table_objects.max_extent_m " +
           fmt(config.max_extent_m) + ")";
  }
  return {};
}

// Step 1's heights: each point's height above the top under it. With
// top_cell_m > 0 that is the mean height of the table-labelled points within
// max_base_height_m of the table's top height in its top_cell_m cell (at
// least kMinCellPoints of them, else the table's top height): a top seen
// tilted (a gravity estimate a few degrees off, a sagging or uneven top)
// otherwise rises above min_height_m at one end and joins everything on it
// into one cluster. Points outside [min_height_m, max_height_m] above their
// local top are then dropped. Returns how many are left.
constexpr int kMinCellPoints = 3;
constexpr int kMaxTopCells = 1 << 20;

int localTops(int r, const LabelImage& labels, const TableObjectConfig& config, Scratch& s) {
  const TableRegion& g = s.regions[static_cast<std::size_t>(r)];
  std::vector<Eigen::Vector3f>& points = s.points[static_cast<std::size_t>(r)];
  std::vector<int>& pixels = s.pixels[static_cast<std::size_t>(r)];
  std::vector<float>& heights = s.heights[static_cast<std::size_t>(r)];
  heights.resize(points.size());
  const float band = config.max_base_height_m;
  float cell = config.top_cell_m;
  int cols = 1, rows = 1;
  if (cell > 0) {
    // A huge table with small cells: coarser cells rather than a huge grid.
    while (true) {
      cols = static_cast<int>((g.x_hi - g.x_lo) / cell) + 1;
      rows = static_cast<int>((g.y_hi - g.y_lo) / cell) + 1;
      if (static_cast<long long>(cols) * rows <= kMaxTopCells) break;
      cell *= 2;
    }
    s.cell_sum.assign(static_cast<std::size_t>(cols) * rows, 0.0);
    s.cell_count.assign(s.cell_sum.size(), 0);
    for (std::size_t k = 0; k < points.size(); ++k) {
      const Eigen::Vector3f& p = points[k];
      if (labels.labels[static_cast<std::size_t>(pixels[k])] != kTableLabel ||
          std::abs(p.z() - g.top) > band) {
        continue;
      }
      const int c = tables_detail::gridCell(p.x(), p.y(), g.x_lo, g.y_lo, cell, cols, rows);
      if (c < 0) continue;
      s.cell_sum[static_cast<std::size_t>(c)] += p.z();
      ++s.cell_count[static_cast<std::size_t>(c)];
    }
    s.cell_top.resize(s.cell_sum.size());
    for (std::size_t c = 0; c < s.cell_sum.size(); ++c) {
      s.cell_top[c] = s.cell_count[c] >= kMinCellPoints
                          ? static_cast<float>(s.cell_sum[c] / s.cell_count[c])
                          : g.top;
    }
  }
  std::size_t kept = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3f p = points[k];
    float top = g.top;
    if (cell > 0) {
      const int c = tables_detail::gridCell(p.x(), p.y(), g.x_lo, g.y_lo, cell, cols, rows);
      if (c >= 0) top = s.cell_top[static_cast<std::size_t>(c)];
    }
    const float h = p.z() - top;
    if (!(h >= config.min_height_m && h <= config.max_height_m)) continue;
    points[kept] = p;
    pixels[kept] = pixels[k];
    heights[kept] = h;
    ++kept;
  }
  points.resize(kept);
  pixels.resize(kept);
  heights.resize(kept);
  return static_cast<int>(kept);
}

// Step 3 for a cluster that does not stand but holds several labels (clutter
// on a desk joined through unlabelled, table or cabinet points between the
// things): each label's points but the table's are clustered alone, and the
// parts that stand become candidates (their points take new cluster indices). One label's
// object is never split: a mug the forest calls half table, half object stands
// as one cluster and is not looked at here. Returns how many parts stand.
int splitByLabel(int r, int c, const LabelImage& labels, const TableObjectConfig& config, int width,
                 int height, Scratch& s, std::vector<ClusterStats>& stats,
                 std::vector<Candidate>& candidates) {
  const auto ur = static_cast<std::size_t>(r);
  const std::vector<Eigen::Vector3f>& points = s.points[ur];
  const std::vector<int>& pixels = s.pixels[ur];
  const std::vector<float>& heights = s.heights[ur];
  std::vector<int>& cluster_of = s.cluster_of[ur];
  const TableRegion& region = s.regions[ur];
  s.split_index.clear();
  std::array<bool, 256> present{};
  int distinct = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (cluster_of[k] != c) continue;
    s.split_index.push_back(static_cast<int>(k));
    const std::uint8_t l = labels.labels[static_cast<std::size_t>(pixels[k])];
    distinct += !present[l];
    present[l] = true;
  }
  if (distinct < 2) return 0;
  int standing = 0;
  for (int l = 0; l < 256; ++l) {
    // Table-labelled parts are more of the table (a raised or tilted part of
    // the top, a second top behind it): measured on NYU's labels, 14 % of the
    // candidates' points were such parts.
    if (!present[static_cast<std::size_t>(l)] || l == kTableLabel) continue;
    s.part_index.clear();
    s.part_points.clear();
    s.part_pixels.clear();
    for (const int k : s.split_index) {
      if (labels.labels[static_cast<std::size_t>(pixels[static_cast<std::size_t>(k)])] != l)
        continue;
      s.part_index.push_back(k);
      s.part_points.push_back(points[static_cast<std::size_t>(k)]);
      s.part_pixels.push_back(pixels[static_cast<std::size_t>(k)]);
    }
    if (static_cast<int>(s.part_points.size()) < config.min_points) continue;
    // Id `parts` (one past the last): the points the sampled clustering left out.
    const int parts = clusterSampled(s.part_points, s.part_pixels, config.cluster_tolerance_m,
                                     width, height, config.point_stride, s.sampled, s.part_of);
    const std::size_t base = stats.size();
    stats.resize(base + static_cast<std::size_t>(parts) + 1);
    for (std::size_t j = 0; j < s.part_index.size(); ++j) {
      const auto k = static_cast<std::size_t>(s.part_index[j]);
      const int id = static_cast<int>(base) + s.part_of[j];
      cluster_of[k] = id;
      addPoint(stats[static_cast<std::size_t>(id)], points[k], pixels[k], heights[k]);
    }
    for (std::size_t id = base; id < stats.size(); ++id) {
      if (stats[id].count >= config.min_points) stats[id].axis = principalAxis(stats[id]);
    }
    for (std::size_t j = 0; j < s.part_index.size(); ++j) {
      ClusterStats& st = stats[base + static_cast<std::size_t>(s.part_of[j])];
      if (st.count >= config.min_points) extendBox(st, s.part_points[j]);
    }
    for (std::size_t id = base; id + 1 < stats.size(); ++id) {
      const ClusterStats& st = stats[id];
      if (st.count < config.min_points ||
          !whyNotStanding(st, region, s.edges.data() + region.first, config).empty()) {
        continue;
      }
      candidates.push_back({r, static_cast<int>(id), region.table, st.count, st.first_pixel});
      ++standing;
    }
  }
  return standing;
}

// Steps 2 and 3 for one region: its candidates appended to `candidates`,
// the clusters dropped counted in `out`.
void clusterRegion(int r, const LabelImage& labels, const TableObjectConfig& config, int width,
                   int height, Scratch& s, std::vector<ClusterStats>& stats,
                   std::vector<Candidate>& candidates, TableObjectDetection& out) {
  const std::vector<Eigen::Vector3f>& points = s.points[static_cast<std::size_t>(r)];
  const std::vector<int>& pixels = s.pixels[static_cast<std::size_t>(r)];
  const TableRegion& region = s.regions[static_cast<std::size_t>(r)];
  std::vector<int>& cluster_of = s.cluster_of[static_cast<std::size_t>(r)];
  stats.clear();
  cluster_of.clear();
  if (points.empty()) return;
  // Id `clusters` (one past the last) holds the points a sampled clustering
  // left in no cluster: never a candidate, not counted as too small.
  const int clusters = clusterSampled(points, pixels, config.cluster_tolerance_m, width, height,
                                      config.point_stride, s.sampled, cluster_of);
  stats.assign(static_cast<std::size_t>(clusters) + 1, ClusterStats{});
  sumClusters(points, pixels, s.heights[static_cast<std::size_t>(r)], cluster_of, stats);
  std::vector<int>& big = s.object_of_cluster;  // here: 1 for clusters of min_points or more
  big.assign(static_cast<std::size_t>(clusters) + 1, 0);
  int too_small = 0;
  for (int c = 0; c < clusters; ++c) {
    ClusterStats& st = stats[static_cast<std::size_t>(c)];
    if (st.count < config.min_points) {
      ++too_small;
      continue;
    }
    big[static_cast<std::size_t>(c)] = 1;
    st.axis = principalAxis(st);
  }
  footprintBoxes(points, cluster_of, big, stats);
  const HalfPlane* edges = s.edges.data() + region.first;
  for (int c = 0; c < clusters; ++c) {
    if (!big[static_cast<std::size_t>(c)]) continue;
    // Copied: a split appends to `stats`.
    const ClusterStats st = stats[static_cast<std::size_t>(c)];
    const std::string why = whyNotStanding(st, region, edges, config);
    if (!why.empty()) {
      ++out.clusters_not_standing;
      const int parts = splitByLabel(r, c, labels, config, width, height, s, stats, candidates);
      out.diagnostics.push_back(
          "table " + std::to_string(region.table) + ": cluster of " + std::to_string(st.count) +
          " points is not an object on it: " + why +
          (parts > 0 ? "; " + std::to_string(parts) + " of its labels' parts stand there"
                     : std::string()));
      continue;
    }
    candidates.push_back({r, c, region.table, st.count, st.first_pixel});
  }
  if (too_small > 0) {
    out.clusters_too_small += too_small;
    out.diagnostics.push_back(
        "table " + std::to_string(region.table) + ": " + std::to_string(too_small) +
        " clusters below table_objects.min_points (" + std::to_string(config.min_points) + ")");
  }
}

void checkInputs(const OrganizedCloud& cloud, const LabelImage& labels) {
  const std::size_t n = cloud.points.size();
  if (cloud.width < 0 || cloud.height < 0 ||
      n != static_cast<std::size_t>(cloud.width) * static_cast<std::size_t>(cloud.height)) {
    throw Error("findTableObjects: cloud is " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height) + " but holds " + std::to_string(n) + " points");
  }
  if (labels.width != cloud.width || labels.height != cloud.height || labels.labels.size() != n) {
    throw Error("findTableObjects: label image is " + std::to_string(labels.width) + "x" +
                std::to_string(labels.height) + " with " + std::to_string(labels.labels.size()) +
                " labels but the cloud is " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height));
  }
}

// Empties `out` keeping its buffers: the objects' pixel lists go to the spares.
void resetDetection(TableObjectDetection& out, Scratch& s) {
  for (TableObject& o : out.objects) {
    if (o.pixels.capacity() > 0 && s.spare_pixels.size() < kMaxSparePixelLists) {
      s.spare_pixels.push_back(std::move(o.pixels));
    }
  }
  out.objects.clear();
  out.diagnostics.clear();
  out.points_above_tops = 0;
  out.clusters_too_small = 0;
  out.clusters_not_standing = 0;
}

}  // namespace

void validateTableObjectConfig(const TableObjectConfig& c) {
  checkRange("min_height_m", c.min_height_m, 0, 1);
  checkRange("max_height_m", c.max_height_m, 0.01, 3);
  if (!(c.min_height_m < c.max_height_m)) {
    badSetting("min_height_m", c.min_height_m,
               "must be below table_objects.max_height_m (" + fmt(c.max_height_m, 6) + ")");
  }
  checkRange("outline_margin_m", c.outline_margin_m, 0, 0.5);
  checkRange("cluster_tolerance_m", c.cluster_tolerance_m, 0.005, 0.5);
  checkRange("min_points", c.min_points, 1, 1000000);
  checkRange("max_base_height_m", c.max_base_height_m, 0, 1);
  if (c.max_base_height_m < c.min_height_m) {
    badSetting("max_base_height_m", c.max_base_height_m,
               "must be at least table_objects.min_height_m (" + fmt(c.min_height_m, 6) +
                   "): no cluster starts lower");
  }
  checkRange("max_extent_m", c.max_extent_m, 0.01, 10);
  checkRange("top_cell_m", c.top_cell_m, 0, 2);
  checkRange("point_stride", c.point_stride, 1, 8);
  if (c.top_cell_m > 0 && c.top_cell_m < 0.01f) {
    badSetting("top_cell_m", c.top_cell_m, "must be 0 (the table's top height) or at least 0.01");
  }
}

void findTableObjectsInto(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                          const std::vector<TableCluster>& tables, const TableObjectConfig& config,
                          TableObjectDetection& out) {
  thread_local Scratch scratch_tls;
  detail::Borrowed scratch(scratch_tls);
  Scratch& s = *scratch;
  resetDetection(out, s);
  if (!config.enabled) return;
  validateTableObjectConfig(config);
  if (cloud_ground.points.empty() || tables.empty()) return;
  checkInputs(cloud_ground, labels);

  buildRegions(tables, config, s, out.diagnostics);
  if (s.regions.empty()) return;
  collectPointsAboveTops(cloud_ground, labels, config.outline_margin_m, s);
  for (int r = 0; r < static_cast<int>(s.regions.size()); ++r) {
    out.points_above_tops += localTops(r, labels, config, s);
  }

  thread_local std::vector<std::vector<ClusterStats>> stats_tls;
  thread_local std::vector<Candidate> candidates_tls;
  detail::Borrowed stats_buffer(stats_tls);
  detail::Borrowed candidates_buffer(candidates_tls);
  std::vector<std::vector<ClusterStats>>& stats = *stats_buffer;
  std::vector<Candidate>& candidates = *candidates_buffer;
  stats.resize(s.regions.size());
  candidates.clear();
  for (int r = 0; r < static_cast<int>(s.regions.size()); ++r) {
    clusterRegion(r, labels, config, cloud_ground.width, cloud_ground.height, s,
                  stats[static_cast<std::size_t>(r)], candidates, out);
  }
  // By table (regions are in table order), then decreasing size, then first pixel.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.region != b.region) return a.region < b.region;
    if (a.count != b.count) return a.count > b.count;
    return a.first_pixel < b.first_pixel;
  });
  out.objects.resize(candidates.size());
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    out.objects[k].id = static_cast<int>(k);
    takePixelBuffer(out.objects[k], s);
  }
  // Per region: which object each cluster became, then the objects' fields.
  std::vector<int>& cluster_of_object = s.cluster_of_object;
  std::size_t k = 0;
  for (int r = 0; r < static_cast<int>(s.regions.size()); ++r) {
    const std::size_t first = k;
    while (k < candidates.size() && candidates[k].region == r) ++k;
    if (k == first) continue;
    const std::vector<ClusterStats>& st = stats[static_cast<std::size_t>(r)];
    s.object_of_cluster.assign(st.size(), -1);
    cluster_of_object.clear();
    for (std::size_t j = first; j < k; ++j) {
      s.object_of_cluster[static_cast<std::size_t>(candidates[j].cluster)] =
          static_cast<int>(j - first);
      cluster_of_object.push_back(candidates[j].cluster);
    }
    describeCandidates(cloud_ground, s.regions[static_cast<std::size_t>(r)],
                       s.edges.data() + s.regions[static_cast<std::size_t>(r)].first,
                       config.outline_margin_m, s.points[static_cast<std::size_t>(r)],
                       s.pixels[static_cast<std::size_t>(r)],
                       s.cluster_of[static_cast<std::size_t>(r)], s.object_of_cluster, st,
                       cluster_of_object, s.sums, out, static_cast<int>(first));
  }
}

TableObjectDetection findTableObjects(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                                      const std::vector<TableCluster>& tables,
                                      const TableObjectConfig& config) {
  TableObjectDetection out;
  findTableObjectsInto(cloud_ground, labels, tables, config, out);
  return out;
}

int relabelTableObjects(const std::vector<TableObject>& objects, LabelImage& labels) {
  const auto n = static_cast<long long>(labels.labels.size());
  // Checked first, so that a bad list leaves the image as it was.
  for (const TableObject& o : objects) {
    for (const int p : o.pixels) {
      if (p < 0 || p >= n) {
        throw Error("relabelTableObjects: object " + std::to_string(o.id) + " has pixel " +
                    std::to_string(p) + ", outside the " + std::to_string(labels.width) + "x" +
                    std::to_string(labels.height) + " label image");
      }
    }
  }
  int changed = 0;
  for (const TableObject& o : objects) {
    for (const int p : o.pixels) {
      std::uint8_t& l = labels.labels[static_cast<std::size_t>(p)];
      if (l != kTableLabel) continue;
      l = kObjectLabel;
      ++changed;
    }
  }
  return changed;
}

}  // namespace findmug
