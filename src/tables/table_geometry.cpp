// table_geometry.cpp — 2-D geometry of one table cluster: top height, the
// top's principal axes on the floor, its oriented box with robust edges, and
// its convex hull (convexHull2d).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "findmug/tables/tables.hpp"
#include "common/min_max2.hpp"
#include "tables/tables_internal.hpp"

namespace findmug {

using namespace tables_detail;

namespace {

// Cell of the floor occupancy grid the axes are computed on (see tables.hpp).
constexpr float kAxisCellM = 0.02f;
// Column width used to pick hull candidates (extremes per column/row). A
// missed hull vertex lies within this of the computed hull.
constexpr float kHullStripM = 0.005f;
// Robust edges (see edgeRange).
constexpr float kEdgeStripM = 0.05f;
constexpr float kEdgeQuantile = 0.8f;

// The passes below put each point in a strip or cell of a grid. They take
// the points kBlock at a time: first every point's strip index, in a plain
// loop the compiler turns into four-wide divisions (IEEE division: the same
// quotient as one at a time), then the per-point updates, which read the
// indices. One division per point and axis was what these passes spent most
// of their time on.
constexpr int kBlock = 256;

// An AlignedBox2f grown point by point (MinMax2, from an empty box's
// highest / lowest): the same result as AlignedBox2f::extend per point, with
// the corners in registers rather than on the stack.
class BoxBuilder2 {
 public:
  // Values in registers (see MinMax2::add).
  void extend(float x, float y) { extremes_.add(x, y); }
  Eigen::AlignedBox2f box() const {
    float lo[2], hi[2];
    extremes_.get(lo, hi);
    return Eigen::AlignedBox2f(Eigen::Vector2f(lo[0], lo[1]), Eigen::Vector2f(hi[0], hi[1]));
  }

 private:
  detail::MinMax2 extremes_{std::numeric_limits<float>::max(),
                            std::numeric_limits<float>::lowest()};
};

// out[k] = min(last, int((values[k * Stride] - origin) / width)), k < count:
// the strip of a coordinate, for points stored as Stride floats each
// (Vector2f: 2, Vector3f: 3), clamped to the last strip.
template <int Stride>
void stripIndices(const float* __restrict values, int count, float origin, float width, int last,
                  int* __restrict out) {
  for (int k = 0; k < count; ++k) {
    const int i = static_cast<int>((values[k * Stride] - origin) / width);
    out[k] = i < last ? i : last;
  }
}

// Coordinate `axis` of points[first] as the start of a strided float array.
inline const float* coordinates(const std::vector<Eigen::Vector2f>& points, std::size_t first,
                                int axis) {
  return points.data()->data() + 2 * first + axis;
}

// cell[k] = row * cols + col of points[first + k], k < count, on a grid of
// `cols` x `rows` cells of edge `edge` from `origin` (clamped to the last
// row and column), via stripIndices.
void gridCells(const std::vector<Eigen::Vector2f>& points, std::size_t first, int count,
               const Eigen::Vector2f& origin, float edge, int cols, int rows, std::size_t* cell) {
  int col_of[kBlock], row_of[kBlock];
  stripIndices<2>(coordinates(points, first, 0), count, origin.x(), edge, cols - 1, col_of);
  stripIndices<2>(coordinates(points, first, 1), count, origin.y(), edge, rows - 1, row_of);
  for (int k = 0; k < count; ++k) {
    cell[k] = static_cast<std::size_t>(row_of[k]) * cols + col_of[k];
  }
}

float cross2(const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Hull candidates: per narrow column the lowest and highest point in y, per
// narrow row the extremes in x. Every hull vertex is, up to the strip width,
// one of them; this cuts 100k top points to a few hundred before sorting.
// `box` is the points' bounding box. The current extremes are kept by value
// next to the arrays (not looked up through an index per point).
void hullCandidates(const std::vector<Eigen::Vector2f>& pts, const Eigen::AlignedBox2f& box,
                    std::vector<Eigen::Vector2f>& out) {
  const Eigen::Vector2f size = box.sizes();
  // Cap the strip count for absurdly large inputs; the strip only sets accuracy.
  const float strip = std::max({kHullStripM, size.x() / 20000.0f, size.y() / 20000.0f});
  const int cols = static_cast<int>(size.x() / strip) + 1;
  const int rows = static_cast<int>(size.y() / strip) + 1;
  // Points are finite, so the first point of a strip always replaces these.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  // Per-thread buffers: no allocation per table once a stream is warm.
  thread_local std::vector<Eigen::Vector2f> col_lo, col_hi, row_lo, row_hi;
  col_lo.assign(cols, Eigen::Vector2f(0.0f, kInf));
  col_hi.assign(cols, Eigen::Vector2f(0.0f, -kInf));
  row_lo.assign(rows, Eigen::Vector2f(kInf, 0.0f));
  row_hi.assign(rows, Eigen::Vector2f(-kInf, 0.0f));
  const float x0 = box.min().x(), y0 = box.min().y();
  // Points in image order run along a row of the top: many in a row fall in
  // one y strip, and that strip's extremes stay in registers until the strip
  // changes (same comparisons in the same order; stores only at the change).
  int r_cur = -1;
  Eigen::Vector2f lo_cur(kInf, 0.0f), hi_cur(-kInf, 0.0f);
  int col_of[kBlock], row_of[kBlock];
  for (std::size_t first = 0; first < pts.size(); first += kBlock) {
    const int m = static_cast<int>(std::min<std::size_t>(kBlock, pts.size() - first));
    stripIndices<2>(coordinates(pts, first, 0), m, x0, strip, cols - 1, col_of);
    stripIndices<2>(coordinates(pts, first, 1), m, y0, strip, rows - 1, row_of);
    for (int j = 0; j < m; ++j) {
      const Eigen::Vector2f& p = pts[first + j];
      const int c = col_of[j], r = row_of[j];
      if (p.y() < col_lo[c].y()) col_lo[c] = p;
      if (p.y() > col_hi[c].y()) col_hi[c] = p;
      if (r != r_cur) {
        if (r_cur >= 0) {
          row_lo[r_cur] = lo_cur;
          row_hi[r_cur] = hi_cur;
        }
        r_cur = r;
        lo_cur = row_lo[r];
        hi_cur = row_hi[r];
      }
      if (p.x() < lo_cur.x()) lo_cur = p;
      if (p.x() > hi_cur.x()) hi_cur = p;
    }
  }
  if (r_cur >= 0) {
    row_lo[r_cur] = lo_cur;
    row_hi[r_cur] = hi_cur;
  }
  out.clear();
  for (const auto* list : {&col_lo, &col_hi, &row_lo, &row_hi}) {
    for (const Eigen::Vector2f& p : *list) {
      if (std::isfinite(p.x()) && std::isfinite(p.y())) out.push_back(p);
    }
  }
}

// Floor area covered by the points: occupied cells of edge `cell` (coarser
// for huge inputs, at most ~4M cells) times the cell area. Unlike the hull's
// area it stays small for a thin strip (the top band of a vertical panel or
// of a chair back, seen from above as a line) and for scattered points.
float occupiedArea(const std::vector<Eigen::Vector2f>& pts, const Eigen::AlignedBox2f& box,
                   float cell) {
  if (pts.empty()) return 0.0f;
  const Eigen::Vector2f size = box.sizes();
  cell = std::max(cell, std::sqrt(size.x() * size.y() / 4.0e6f));
  const int cols = static_cast<int>(size.x() / cell) + 1;
  const int rows = static_cast<int>(size.y() / cell) + 1;
  thread_local std::vector<std::uint8_t> occupied;
  occupied.assign(static_cast<std::size_t>(cols) * rows, 0);
  int count = 0;
  // Consecutive points mostly share a cell: testing the previous cell first
  // spares the load that would wait for the previous point's store.
  std::size_t last = std::numeric_limits<std::size_t>::max();
  std::size_t cell_of[kBlock];
  for (std::size_t first = 0; first < pts.size(); first += kBlock) {
    const int m = static_cast<int>(std::min<std::size_t>(kBlock, pts.size() - first));
    gridCells(pts, first, m, box.min(), cell, cols, rows, cell_of);
    for (int j = 0; j < m; ++j) {
      const std::size_t k = cell_of[j];
      if (k == last) continue;
      last = k;
      std::uint8_t& o = occupied[k];
      count += o == 0 ? 1 : 0;
      o = 1;
    }
  }
  return static_cast<float>(count) * cell * cell;
}

// Principal axes of the top on the floor, from the occupied cells of a
// kAxisCellM grid (each cell's mean point counts once), so that point
// density (higher near the camera) does not bias the axes.
// `box` is the points' bounding box.
void principalAxes(const std::vector<Eigen::Vector2f>& pts, const Eigen::AlignedBox2f& box,
                   Eigen::Vector2f& major, Eigen::Vector2f& minor) {
  const Eigen::Vector2f size = box.sizes();
  // Coarser cells for huge inputs keep the grid below ~4M cells.
  const float cell = std::max(kAxisCellM, std::sqrt(size.x() * size.y() / 4.0e6f));
  const int cols = static_cast<int>(size.x() / cell) + 1;
  const int rows = static_cast<int>(size.y() / cell) + 1;
  thread_local std::vector<Eigen::Vector2f> sums;
  thread_local std::vector<int> counts;
  sums.assign(static_cast<std::size_t>(cols) * rows, Eigen::Vector2f::Zero());
  counts.assign(sums.size(), 0);
  // The current cell's sum and count stay in registers while consecutive
  // points fall in it (the same additions in the same order as updating the
  // cell point by point, without each waiting for the last one's store).
  std::size_t k_cur = 0;
  Eigen::Vector2f sum_cur = sums[0];
  int count_cur = counts[0];
  std::size_t cell_of[kBlock];
  for (std::size_t first = 0; first < pts.size(); first += kBlock) {
    const int m = static_cast<int>(std::min<std::size_t>(kBlock, pts.size() - first));
    gridCells(pts, first, m, box.min(), cell, cols, rows, cell_of);
    for (int j = 0; j < m; ++j) {
      const std::size_t k = cell_of[j];
      if (k != k_cur) {
        sums[k_cur] = sum_cur;
        counts[k_cur] = count_cur;
        k_cur = k;
        sum_cur = sums[k];
        count_cur = counts[k];
      }
      // Relative to the box corner: keeps float sums precise far from the robot.
      sum_cur += pts[first + j] - box.min();
      ++count_cur;
    }
  }
  sums[k_cur] = sum_cur;
  counts[k_cur] = count_cur;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  int occupied = 0;
  for (std::size_t k = 0; k < sums.size(); ++k) {
    if (counts[k] == 0) continue;
    const Eigen::Vector2d q = (sums[k] / static_cast<float>(counts[k])).cast<double>();
    mean += q;
    scatter += q * q.transpose();
    ++occupied;
  }
  mean /= occupied;
  const Eigen::Matrix2d cov = scatter / occupied - mean * mean.transpose();
  // Closed-form eigenvector of the larger eigenvalue of a symmetric 2x2.
  const double angle = 0.5 * std::atan2(2.0 * cov(0, 1), cov(0, 0) - cov(1, 1));
  major = Eigen::Vector2f(static_cast<float>(std::cos(angle)), static_cast<float>(std::sin(angle)));
  // Fixed sign so that the same table gives the same axes frame to frame.
  if (major.x() < 0.0f || (major.x() == 0.0f && major.y() < 0.0f)) major = -major;
  minor = Eigen::Vector2f(-major.y(), major.x());
}

// Edges of the top along axis `across`, robust to depth noise. Points are
// cut into strips of kEdgeStripM along axis `along`; each strip's extreme
// points are its edge samples, and the edges are the kEdgeQuantile-th most
// outward of those (per side). Why not the plain extremes: the far edge of a
// top is seen at a grazing angle, where depth noise (1 cm at 2.5 m) pushes
// the most outward of hundreds of points 2-3 cm past the true edge. A high
// quantile rather than the median keeps round tops (whose strips are shorter
// towards the ends) within 1-2 % of their radius. Returns (low, high).
// [lo_along, hi_along] is the points' range along `along`.
Eigen::Vector2f edgeRange(const std::vector<Eigen::Vector2f>& local, int along, int across,
                          float lo_along, float hi_along) {
  const int strips = std::min(4096, static_cast<int>((hi_along - lo_along) / kEdgeStripM) + 1);
  const float strip_width = std::max(kEdgeStripM, (hi_along - lo_along) / strips * 1.0001f);
  thread_local std::vector<float> strip_lo, strip_hi, lows, highs;
  thread_local std::vector<int> strip_count;
  strip_lo.assign(static_cast<std::size_t>(strips), std::numeric_limits<float>::max());
  strip_hi.assign(static_cast<std::size_t>(strips), std::numeric_limits<float>::lowest());
  strip_count.assign(static_cast<std::size_t>(strips), 0);
  // The current strip's extremes and count in registers while consecutive
  // points stay in it (as in principalAxes).
  int k_cur = 0;
  float lo_cur = strip_lo[0], hi_cur = strip_hi[0];
  int count_cur = 0;
  int strip_of[kBlock];
  for (std::size_t first = 0; first < local.size(); first += kBlock) {
    const int m = static_cast<int>(std::min<std::size_t>(kBlock, local.size() - first));
    stripIndices<2>(coordinates(local, first, along), m, lo_along, strip_width, strips - 1,
                    strip_of);
    for (int j = 0; j < m; ++j) {
      const int k = strip_of[j];
      const float v = local[first + j][across];
      if (k != k_cur) {
        strip_lo[k_cur] = lo_cur;
        strip_hi[k_cur] = hi_cur;
        strip_count[k_cur] = count_cur;
        k_cur = k;
        lo_cur = strip_lo[k];
        hi_cur = strip_hi[k];
        count_cur = strip_count[k];
      }
      lo_cur = std::min(lo_cur, v);
      hi_cur = std::max(hi_cur, v);
      ++count_cur;
    }
  }
  strip_lo[k_cur] = lo_cur;
  strip_hi[k_cur] = hi_cur;
  strip_count[k_cur] = count_cur;
  lows.clear();
  highs.clear();
  for (int k = 0; k < strips; ++k) {
    // A strip of one or two points says little about an edge.
    if (strip_count[k] >= 3) {
      lows.push_back(strip_lo[k]);
      highs.push_back(strip_hi[k]);
    }
  }
  if (lows.empty()) {  // tiny clusters: plain extremes
    for (int k = 0; k < strips; ++k) {
      if (strip_count[k] > 0) {
        lows.push_back(strip_lo[k]);
        highs.push_back(strip_hi[k]);
      }
    }
  }
  const auto quantile = [](std::vector<float>& v, float q) {
    const auto k = static_cast<std::size_t>(q * static_cast<float>(v.size() - 1) + 0.5f);
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  };
  return Eigen::Vector2f(quantile(lows, 1.0f - kEdgeQuantile), quantile(highs, kEdgeQuantile));
}

struct TopBand {
  Eigen::Vector3d sum;      // of the band's points, in point order
  Eigen::AlignedBox2f box;  // of their (x, y)
};

// The points within `band` of `height`: their (x, y) into `top` (in point
// order), the sum of the points and the box of their (x, y). A function of
// its own, with plain locals and a cursor into room for every point: written
// inside describeCluster with push_back and Eigen objects, the compiler kept
// the box, the sums and even the height in memory, and each point waited for
// the previous one's stores. The same operations in the same order (Eigen's
// += per coordinate; the box as BoxBuilder2).
__attribute__((noinline)) TopBand topBand(const std::vector<Eigen::Vector3f>& points,
                                          float height, float band,
                                          std::vector<Eigen::Vector2f>& top) {
  top.resize(points.size());
  Eigen::Vector2f* top_end = top.data();
  double sum_x = 0.0, sum_y = 0.0, sum_z = 0.0;
  BoxBuilder2 builder;
  for (const auto& p : points) {
    if (std::abs(p.z() - height) <= band) {
      *top_end = p.head<2>();
      builder.extend(p.x(), p.y());
      ++top_end;
      sum_x += static_cast<double>(p.x());
      sum_y += static_cast<double>(p.y());
      sum_z += static_cast<double>(p.z());
    }
  }
  top.resize(static_cast<std::size_t>(top_end - top.data()));
  return {Eigen::Vector3d(sum_x, sum_y, sum_z), builder.box()};
}

// Lowest and highest z of `points` (not empty, finite). Four running
// extremes instead of one: each point then waits for the one four back, not
// for the last. Only which of a +0 and a -0 comes out can differ from one
// running pair, and describeCluster uses the range only through z - z_min
// for z != 0 and z_max - z_min, where that sign makes no difference.
std::pair<float, float> heightRange(const std::vector<Eigen::Vector3f>& points) {
  float lo[4], hi[4];
  for (int j = 0; j < 4; ++j) {
    lo[j] = std::numeric_limits<float>::max();
    hi[j] = std::numeric_limits<float>::lowest();
  }
  const std::size_t n = points.size(), n4 = n - n % 4;
  for (std::size_t i = 0; i < n4; i += 4) {
    for (int j = 0; j < 4; ++j) {
      const float z = points[i + j].z();
      lo[j] = z < lo[j] ? z : lo[j];
      hi[j] = z > hi[j] ? z : hi[j];
    }
  }
  for (std::size_t i = n4; i < n; ++i) {
    const float z = points[i].z();
    lo[0] = z < lo[0] ? z : lo[0];
    hi[0] = z > hi[0] ? z : hi[0];
  }
  return {std::min({lo[0], lo[1], lo[2], lo[3]}), std::max({hi[0], hi[1], hi[2], hi[3]})};
}

}  // namespace

namespace {

// convexHull2d's work: sorts `points` in place and writes the hull into
// `hull` (whose memory is reused).
void convexHullInto(std::vector<Eigen::Vector2f>& points, std::vector<Eigen::Vector2f>& hull) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) {
    hull.assign(points.begin(), points.end());
    return;
  }
  // Andrew's monotone chain; popping on cross <= 0 drops collinear points.
  hull.resize(2 * points.size());
  std::size_t k = 0;
  for (const auto& p : points) {
    while (k >= 2 && cross2(hull[k - 2], hull[k - 1], p) <= 0.0f) --k;
    hull[k++] = p;
  }
  for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
    const auto& p = points[i];
    while (k >= lower && cross2(hull[k - 2], hull[k - 1], p) <= 0.0f) --k;
    hull[k++] = p;
  }
  hull.resize(k - 1);  // the last point repeats the first
}

}  // namespace

std::vector<Eigen::Vector2f> convexHull2d(std::vector<Eigen::Vector2f> points) {
  std::vector<Eigen::Vector2f> hull;
  convexHullInto(points, hull);
  return hull;
}

ClusterOutcome tables_detail::describeCluster(const std::vector<Eigen::Vector3f>& points,
                                              int point_count, const TableConfig& config,
                                              TableCluster& table) {
  ClusterOutcome outcome;
  const int n = point_count;

  // Top height: the densest height band (the top is the one large horizontal
  // surface; legs, aprons and lower shelves hold fewer points), refined by the
  // mean height of the points within half a band of it.
  const auto [z_min, z_max] = heightRange(points);
  constexpr float kBin = 0.01f;
  const int bins = static_cast<int>((z_max - z_min) / kBin) + 1;
  // Per-thread buffers: no allocation per table once a stream is warm.
  thread_local std::vector<int> histogram;
  thread_local std::vector<Eigen::Vector2f> top, local, candidates;
  histogram.assign(static_cast<std::size_t>(bins), 0);
  {
    // Neighbouring points of a top share a bin: count a run, then add it.
    int b_cur = 0, run = 0;
    int bin_of[kBlock];
    for (std::size_t first = 0; first < points.size(); first += kBlock) {
      const int m = static_cast<int>(std::min<std::size_t>(kBlock, points.size() - first));
      stripIndices<3>(points.data()->data() + 3 * first + 2, m, z_min, kBin, bins - 1, bin_of);
      for (int j = 0; j < m; ++j) {
        if (bin_of[j] != b_cur) {
          histogram[b_cur] += run;
          b_cur = bin_of[j];
          run = 0;
        }
        ++run;
      }
    }
    histogram[b_cur] += run;
  }
  const int half_window = std::max(0, static_cast<int>(config.top_band_m / (2.0f * kBin)));
  int best_bin = 0;
  long best_count = -1;
  long window = 0;
  // Sliding window sum centred on each bin.
  for (int b = 0; b < std::min(bins, half_window); ++b) window += histogram[b];
  for (int b = 0; b < bins; ++b) {
    if (b + half_window < bins) window += histogram[b + half_window];
    if (b - half_window - 1 >= 0) window -= histogram[b - half_window - 1];
    if (window > best_count) {
      best_count = window;
      best_bin = b;
    }
  }
  const float peak = z_min + (static_cast<float>(best_bin) + 0.5f) * kBin;
  double z_sum = 0.0;
  int z_count = 0;
  for (const auto& p : points) {
    if (std::abs(p.z() - peak) <= 0.5f * config.top_band_m) {
      z_sum += p.z();
      ++z_count;
    }
  }
  table.top_height = z_count > 0 ? static_cast<float>(z_sum / z_count) : peak;

  const TopBand band = topBand(points, table.top_height, config.top_band_m, top);
  const Eigen::Vector3d& centroid = band.sum;
  const Eigen::AlignedBox2f& top_box = band.box;
  table.point_count = n;
  if (top.size() < 3) {
    outcome.reason = "degenerate cluster of " + std::to_string(n) + " points: only " +
                     std::to_string(top.size()) + " top points";
    return outcome;
  }
  table.centroid = (centroid / static_cast<double>(top.size())).cast<float>();

  principalAxes(top, top_box, table.major_axis, table.minor_axis);
  const Eigen::Vector2f origin = table.centroid.head<2>();
  local.resize(top.size());  // (along major, along minor) relative to the centroid
  BoxBuilder2 local_builder;
  for (std::size_t k = 0; k < top.size(); ++k) {
    const Eigen::Vector2f q = top[k] - origin;
    const float along = q.dot(table.major_axis), across = q.dot(table.minor_axis);
    local[k] = Eigen::Vector2f(along, across);
    local_builder.extend(along, across);
  }
  const Eigen::AlignedBox2f local_box = local_builder.box();
  const Eigen::Vector2f minor_range =
      edgeRange(local, 0, 1, local_box.min().x(), local_box.max().x());
  const Eigen::Vector2f major_range =
      edgeRange(local, 1, 0, local_box.min().y(), local_box.max().y());
  table.extents = Eigen::Vector2f(0.5f * (major_range[1] - major_range[0]),
                                  0.5f * (minor_range[1] - minor_range[0]));
  table.center = origin + table.major_axis * 0.5f * (major_range[1] + major_range[0]) +
                 table.minor_axis * 0.5f * (minor_range[1] + minor_range[0]);
  const float width = 2.0f * table.extents.y();
  if (!(width >= config.min_table_width_m)) {
    outcome.reason = "degenerate or narrow cluster of " + std::to_string(n) +
                     " points: " + fmt(width) +
                     " m wide along its second axis, below tables.min_table_width_m (" +
                     fmt(config.min_table_width_m) + ")";
    return outcome;
  }
  hullCandidates(top, top_box, candidates);
  convexHullInto(candidates, table.hull);
  table.top_area_m2 = occupiedArea(top, top_box, config.cluster_tolerance_m);
  if (table.hull.size() < 3) {
    outcome.reason = "degenerate cluster of " + std::to_string(n) + " points: its top has no area";
    return outcome;
  }
  outcome.ok = true;
  return outcome;
}

}  // namespace findmug
