// tables.cpp — table clusters and search positions from a labelled cloud.
//
// Clustering: our own exact Euclidean clustering on a hashed voxel grid
// rather than PCL's EuclideanClusterExtraction. Both give the same partition
// (points linked by chains of steps <= tolerance), but PCL builds a kd-tree
// and runs one radius search per point, which for the 20-100k table points
// of a close table costs tens of milliseconds; the stage budget is 20 ms.
// Here the voxel edge is tolerance/sqrt(3), so all points of one voxel are
// within the tolerance of each other and are linked for free; voxels are
// then joined with union-find, testing point pairs only for neighbouring
// voxels (up to two voxels apart) that are not already joined and whose
// bounding boxes come within the tolerance. On a dense table top almost
// every voxel pair is already joined, so the cost is close to one hash
// insert per point. The organized grid is not used for neighbourhoods
// because parts of one table split by an occluder (a chair back, a mug) must
// still join when they are close in 3-D.
//
// Reachability: the grid of observed floor and the buckets of obstacle
// points are built only over the region around the search positions, in one
// pass over the cloud.
#include "findmug/tables.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <sstream>
#include <string>

#include "findmug/error.hpp"
#include "findmug/labels.hpp"

namespace findmug {

namespace {

constexpr std::uint8_t kTableLabel = static_cast<std::uint8_t>(Label::Table);
constexpr std::uint8_t kFloorLabel = static_cast<std::uint8_t>(Label::Floor);
// Points further than this from the robot are corrupt, not far: no RGB-D
// sensor sees 100 m. Keeps voxel coordinates inside their 21-bit fields.
constexpr float kMaxPlausibleRangeM = 100.0f;
// Smallest clustering tolerance: below a millimetre voxel indices would
// overflow their fields at 100 m, and no depth sensor resolves it anyway.
constexpr float kMinToleranceM = 0.001f;
// Cell of the floor occupancy grid the axes are computed on (see header).
constexpr float kAxisCellM = 0.02f;
// Column width used to pick hull candidates (extremes per column/row). A
// missed hull vertex lies within this of the computed hull.
constexpr float kHullStripM = 0.005f;
// Robust edges (see edgeRange).
constexpr float kEdgeStripM = 0.05f;
constexpr float kEdgeQuantile = 0.8f;

bool finitePoint(const Eigen::Vector3f& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

std::string fmt(double value, int precision = 3) {
  std::ostringstream out;
  out.precision(precision);
  out << value;
  return out.str();
}

[[noreturn]] void badSetting(const std::string& key, double value, const std::string& rule) {
  throw Error("tables." + key + " = " + fmt(value, 6) + ": " + rule);
}

}  // namespace

void validateTableConfig(const TableConfig& c) {
  auto positive = [](const char* key, float v) {
    if (!std::isfinite(v) || v <= 0.0f) badSetting(key, v, "must be a positive number");
  };
  auto nonNegative = [](const char* key, float v) {
    if (!std::isfinite(v) || v < 0.0f) badSetting(key, v, "must be a number >= 0");
  };
  if (!std::isfinite(c.cluster_tolerance_m) || c.cluster_tolerance_m < kMinToleranceM) {
    badSetting("cluster_tolerance_m", c.cluster_tolerance_m, "must be at least 0.001 m");
  }
  if (c.min_cluster_points < 1)
    badSetting("min_cluster_points", c.min_cluster_points, "must be >= 1");
  if (c.max_cluster_points < c.min_cluster_points) {
    badSetting("max_cluster_points", c.max_cluster_points,
               "must not be below tables.min_cluster_points (" +
                   std::to_string(c.min_cluster_points) + ")");
  }
  nonNegative("safety_distance_m", c.safety_distance_m);
  positive("arm_reach_m", c.arm_reach_m);
  nonNegative("robot_radius_m", c.robot_radius_m);
  nonNegative("min_table_height_m", c.min_table_height_m);
  positive("max_table_height_m", c.max_table_height_m);
  if (c.max_table_height_m <= c.min_table_height_m) {
    badSetting("max_table_height_m", c.max_table_height_m,
               "must be above tables.min_table_height_m (" + fmt(c.min_table_height_m) + ")");
  }
  positive("top_band_m", c.top_band_m);
  nonNegative("min_table_width_m", c.min_table_width_m);
  nonNegative("obstacle_min_height_m", c.obstacle_min_height_m);
  positive("robot_height_m", c.robot_height_m);
  if (c.robot_height_m <= c.obstacle_min_height_m) {
    badSetting("robot_height_m", c.robot_height_m,
               "must be above tables.obstacle_min_height_m (" + fmt(c.obstacle_min_height_m) + ")");
  }
  if (c.obstacle_min_points < 1) {
    badSetting("obstacle_min_points", c.obstacle_min_points, "must be >= 1");
  }
  nonNegative("floor_tolerance_m", c.floor_tolerance_m);
  positive("floor_cell_m", c.floor_cell_m);
  if (!std::isfinite(c.min_floor_observed_fraction) || c.min_floor_observed_fraction < 0.0f ||
      c.min_floor_observed_fraction > 1.0f) {
    badSetting("min_floor_observed_fraction", c.min_floor_observed_fraction, "must be in [0, 1]");
  }
}

namespace {

// ---------------------------------------------------------------------------
// Exact Euclidean clustering on a hashed voxel grid.

// Open-addressing hash map from packed voxel keys to dense voxel ids.
class VoxelIndex {
 public:
  explicit VoxelIndex(std::size_t expected) {
    std::size_t capacity = 16;
    while (capacity < 2 * expected) capacity <<= 1;
    keys_.assign(capacity, kEmpty);
    values_.assign(capacity, -1);
    mask_ = capacity - 1;
  }
  // Id of `key`, inserting it with `next_id` when absent.
  int findOrInsert(std::uint64_t key, int next_id, bool& inserted) {
    std::size_t slot = hash(key);
    while (true) {
      if (keys_[slot] == key) {
        inserted = false;
        return values_[slot];
      }
      if (keys_[slot] == kEmpty) {
        keys_[slot] = key;
        values_[slot] = next_id;
        inserted = true;
        return next_id;
      }
      slot = (slot + 1) & mask_;
    }
  }
  int find(std::uint64_t key) const {
    std::size_t slot = hash(key);
    while (keys_[slot] != kEmpty) {
      if (keys_[slot] == key) return values_[slot];
      slot = (slot + 1) & mask_;
    }
    return -1;
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // never a packed key (63 bits)
  std::size_t hash(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_;
  }
  std::vector<std::uint64_t> keys_;
  std::vector<int> values_;
  std::size_t mask_ = 0;
};

class DisjointSets {
 public:
  explicit DisjointSets(int n) : parent_(static_cast<std::size_t>(n)) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int find(int x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];  // path halving
      x = parent_[x];
    }
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<int> parent_;
};

constexpr int kFieldBits = 21;
constexpr std::int64_t kFieldOffset = std::int64_t{1} << (kFieldBits - 1);

std::uint64_t packVoxel(std::int64_t ix, std::int64_t iy, std::int64_t iz) {
  return (static_cast<std::uint64_t>(ix + kFieldOffset) << (2 * kFieldBits)) |
         (static_cast<std::uint64_t>(iy + kFieldOffset) << kFieldBits) |
         static_cast<std::uint64_t>(iz + kFieldOffset);
}

// Squared distance between two axis-aligned boxes (0 when they overlap).
float squaredGap(const Eigen::AlignedBox3f& a, const Eigen::AlignedBox3f& b) {
  float gap2 = 0.0f;
  for (int axis = 0; axis < 3; ++axis) {
    const float g = std::max({0.0f, b.min()[axis] - a.max()[axis], a.min()[axis] - b.max()[axis]});
    gap2 += g * g;
  }
  return gap2;
}

std::vector<int> clusterPoints(const std::vector<Eigen::Vector3f>& points, float tolerance) {
  const int n = static_cast<int>(points.size());
  std::vector<int> labels(points.size(), -1);
  if (n == 0) return labels;

  // Slightly under tolerance/sqrt(3) so the voxel diagonal never exceeds the
  // tolerance through rounding; then neighbours within the tolerance are at
  // most `reach` voxels away on each axis.
  // With tolerance >= kMinToleranceM and points within kMaxPlausibleRangeM,
  // voxel indices stay well inside their 21-bit fields.
  const float voxel = tolerance / std::sqrt(3.0f) * 0.999f;
  const int reach = static_cast<int>(std::ceil(tolerance / voxel));
  const float tol2 = tolerance * tolerance;

  VoxelIndex index(points.size());
  std::vector<int> point_voxel(points.size());
  std::vector<Eigen::Vector3i> voxel_coords;
  const float inv_voxel = 1.0f / voxel;
  std::uint64_t last_key = ~std::uint64_t{0};
  int last_voxel = -1;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = points[i];
    const Eigen::Vector3i c(static_cast<int>(std::floor(p.x() * inv_voxel)),
                            static_cast<int>(std::floor(p.y() * inv_voxel)),
                            static_cast<int>(std::floor(p.z() * inv_voxel)));
    const std::uint64_t key = packVoxel(c.x(), c.y(), c.z());
    // Points come in image order, so neighbours often share a voxel.
    if (key != last_key) {
      bool inserted = false;
      last_voxel = index.findOrInsert(key, static_cast<int>(voxel_coords.size()), inserted);
      last_key = key;
      if (inserted) voxel_coords.push_back(c);
    }
    point_voxel[i] = last_voxel;
  }
  const int voxels = static_cast<int>(voxel_coords.size());

  // Points grouped by voxel (counting sort) and each voxel's bounding box.
  std::vector<int> start(static_cast<std::size_t>(voxels) + 1, 0);
  for (int v : point_voxel) ++start[v + 1];
  for (int v = 0; v < voxels; ++v) start[v + 1] += start[v];
  std::vector<int> order(points.size());
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int i = 0; i < n; ++i) order[fill[point_voxel[i]]++] = i;
  }
  std::vector<Eigen::AlignedBox3f> boxes(static_cast<std::size_t>(voxels));
  for (int v = 0; v < voxels; ++v) {
    for (int k = start[v]; k < start[v + 1]; ++k) boxes[v].extend(points[order[k]]);
  }

  // Points copied in voxel order: the pair tests below then read memory
  // sequentially.
  std::vector<Eigen::Vector3f> sorted(points.size());
  for (int k = 0; k < n; ++k) sorted[k] = points[order[k]];

  // Forward half of the neighbourhood (each unordered voxel pair once), the
  // touching voxels first: on a dense surface they join nearly everything,
  // so the farther pairs are then mostly skipped as already joined.
  std::vector<Eigen::Vector3i> offsets;
  for (int ring = 1; ring <= reach; ++ring) {
    for (int dz = -ring; dz <= ring; ++dz) {
      for (int dy = -ring; dy <= ring; ++dy) {
        for (int dx = -ring; dx <= ring; ++dx) {
          const bool forward = dz > 0 || (dz == 0 && (dy > 0 || (dy == 0 && dx > 0)));
          const int chebyshev = std::max({std::abs(dx), std::abs(dy), std::abs(dz)});
          if (forward && chebyshev == ring) offsets.emplace_back(dx, dy, dz);
        }
      }
    }
  }

  DisjointSets sets(voxels);
  std::vector<int> near_a, near_b;
  for (const Eigen::Vector3i& d : offsets) {
    for (int a = 0; a < voxels; ++a) {
      const Eigen::Vector3i& ca = voxel_coords[a];
      const int b = index.find(packVoxel(static_cast<std::int64_t>(ca.x()) + d.x(),
                                         static_cast<std::int64_t>(ca.y()) + d.y(),
                                         static_cast<std::int64_t>(ca.z()) + d.z()));
      if (b < 0 || sets.find(a) == sets.find(b)) continue;
      if (squaredGap(boxes[a], boxes[b]) > tol2) continue;
      // Only points within the tolerance of the other voxel's box can link.
      near_a.clear();
      near_b.clear();
      for (int k = start[a]; k < start[a + 1]; ++k) {
        if (boxes[b].squaredExteriorDistance(sorted[k]) <= tol2) near_a.push_back(k);
      }
      if (near_a.empty()) continue;
      for (int k = start[b]; k < start[b + 1]; ++k) {
        if (boxes[a].squaredExteriorDistance(sorted[k]) <= tol2) near_b.push_back(k);
      }
      bool linked = false;
      for (std::size_t i = 0; i < near_a.size() && !linked; ++i) {
        const Eigen::Vector3f& p = sorted[near_a[i]];
        for (int k : near_b) {
          if ((sorted[k] - p).squaredNorm() <= tol2) {
            linked = true;
            break;
          }
        }
      }
      if (linked) sets.unite(a, b);
    }
  }

  // Dense cluster ids in order of first appearance.
  std::vector<int> root_label(static_cast<std::size_t>(voxels), -1);
  int next = 0;
  for (int i = 0; i < n; ++i) {
    const int root = sets.find(point_voxel[i]);
    if (root_label[root] < 0) root_label[root] = next++;
    labels[i] = root_label[root];
  }
  return labels;
}

// ---------------------------------------------------------------------------
// Geometry of one cluster.

float cross2(const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Hull candidates: per narrow column the lowest and highest point in y, per
// narrow row the extremes in x. Every hull vertex is, up to the strip width,
// one of them; this cuts 100k top points to a few hundred before sorting.
std::vector<Eigen::Vector2f> hullCandidates(const std::vector<Eigen::Vector2f>& pts) {
  Eigen::AlignedBox2f box;
  for (const auto& p : pts) box.extend(p);
  const Eigen::Vector2f size = box.sizes();
  // Cap the strip count for absurdly large inputs; the strip only sets accuracy.
  const float strip = std::max({kHullStripM, size.x() / 20000.0f, size.y() / 20000.0f});
  const int cols = static_cast<int>(size.x() / strip) + 1;
  const int rows = static_cast<int>(size.y() / strip) + 1;
  constexpr int kNone = -1;
  std::vector<int> col_lo(cols, kNone), col_hi(cols, kNone), row_lo(rows, kNone),
      row_hi(rows, kNone);
  for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
    const Eigen::Vector2f& p = pts[i];
    const int c = std::min(cols - 1, static_cast<int>((p.x() - box.min().x()) / strip));
    const int r = std::min(rows - 1, static_cast<int>((p.y() - box.min().y()) / strip));
    if (col_lo[c] == kNone || p.y() < pts[col_lo[c]].y()) col_lo[c] = i;
    if (col_hi[c] == kNone || p.y() > pts[col_hi[c]].y()) col_hi[c] = i;
    if (row_lo[r] == kNone || p.x() < pts[row_lo[r]].x()) row_lo[r] = i;
    if (row_hi[r] == kNone || p.x() > pts[row_hi[r]].x()) row_hi[r] = i;
  }
  std::vector<Eigen::Vector2f> out;
  for (const auto* list : {&col_lo, &col_hi, &row_lo, &row_hi}) {
    for (int i : *list) {
      if (i != kNone) out.push_back(pts[i]);
    }
  }
  return out;
}

// Principal axes of the top on the floor, from the occupied cells of a
// kAxisCellM grid (each cell's mean point counts once), so that point
// density (higher near the camera) does not bias the axes.
void principalAxes(const std::vector<Eigen::Vector2f>& pts, Eigen::Vector2f& major,
                   Eigen::Vector2f& minor) {
  Eigen::AlignedBox2f box;
  for (const auto& p : pts) box.extend(p);
  const Eigen::Vector2f size = box.sizes();
  // Coarser cells for huge inputs keep the grid below ~4M cells.
  const float cell = std::max(kAxisCellM, std::sqrt(size.x() * size.y() / 4.0e6f));
  const int cols = static_cast<int>(size.x() / cell) + 1;
  const int rows = static_cast<int>(size.y() / cell) + 1;
  std::vector<Eigen::Vector2f> sums(static_cast<std::size_t>(cols) * rows, Eigen::Vector2f::Zero());
  std::vector<int> counts(sums.size(), 0);
  for (const auto& p : pts) {
    const int c = std::min(cols - 1, static_cast<int>((p.x() - box.min().x()) / cell));
    const int r = std::min(rows - 1, static_cast<int>((p.y() - box.min().y()) / cell));
    const std::size_t k = static_cast<std::size_t>(r) * cols + c;
    // Relative to the box corner: keeps float sums precise far from the robot.
    sums[k] += p - box.min();
    ++counts[k];
  }
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
Eigen::Vector2f edgeRange(const std::vector<Eigen::Vector2f>& local, int along, int across) {
  float lo_along = std::numeric_limits<float>::max();
  float hi_along = std::numeric_limits<float>::lowest();
  for (const auto& q : local) {
    lo_along = std::min(lo_along, q[along]);
    hi_along = std::max(hi_along, q[along]);
  }
  const int strips = std::min(4096, static_cast<int>((hi_along - lo_along) / kEdgeStripM) + 1);
  const float strip_width = std::max(kEdgeStripM, (hi_along - lo_along) / strips * 1.0001f);
  std::vector<float> strip_lo(static_cast<std::size_t>(strips), std::numeric_limits<float>::max());
  std::vector<float> strip_hi(static_cast<std::size_t>(strips),
                              std::numeric_limits<float>::lowest());
  std::vector<int> strip_count(static_cast<std::size_t>(strips), 0);
  for (const auto& q : local) {
    const int k = std::min(strips - 1, static_cast<int>((q[along] - lo_along) / strip_width));
    strip_lo[k] = std::min(strip_lo[k], q[across]);
    strip_hi[k] = std::max(strip_hi[k], q[across]);
    ++strip_count[k];
  }
  std::vector<float> lows, highs;
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

struct ClusterOutcome {
  bool ok = false;
  std::string reason;  // why not
};

// Fills `table` (all but id and search positions) from the cluster's points.
ClusterOutcome describeCluster(const std::vector<Eigen::Vector3f>& points,
                               const std::vector<float>& confidence, const TableConfig& config,
                               TableCluster& table) {
  ClusterOutcome outcome;
  const int n = static_cast<int>(points.size());

  // Top height: the densest height band (the top is the one large horizontal
  // surface; legs, aprons and lower shelves hold fewer points), refined by the
  // mean height of the points within half a band of it.
  float z_min = std::numeric_limits<float>::max(), z_max = std::numeric_limits<float>::lowest();
  for (const auto& p : points) {
    z_min = std::min(z_min, p.z());
    z_max = std::max(z_max, p.z());
  }
  constexpr float kBin = 0.01f;
  const int bins = static_cast<int>((z_max - z_min) / kBin) + 1;
  std::vector<int> histogram(static_cast<std::size_t>(bins), 0);
  for (const auto& p : points)
    ++histogram[std::min(bins - 1, static_cast<int>((p.z() - z_min) / kBin))];
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

  std::vector<Eigen::Vector2f> top;
  top.reserve(points.size());
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : points) {
    if (std::abs(p.z() - table.top_height) <= config.top_band_m) {
      top.push_back(p.head<2>());
      centroid += p.cast<double>();
    }
  }
  table.point_count = n;
  double confidence_sum = 0.0;
  for (float c : confidence) confidence_sum += c;
  table.mean_confidence = n > 0 ? static_cast<float>(confidence_sum / n) : 0.0f;
  if (top.size() < 3) {
    outcome.reason = "degenerate cluster of " + std::to_string(n) + " points: only " +
                     std::to_string(top.size()) + " top points";
    return outcome;
  }
  table.centroid = (centroid / static_cast<double>(top.size())).cast<float>();

  principalAxes(top, table.major_axis, table.minor_axis);
  const Eigen::Vector2f origin = table.centroid.head<2>();
  std::vector<Eigen::Vector2f> local;  // (along major, along minor) relative to the centroid
  local.reserve(top.size());
  for (const auto& p : top) {
    const Eigen::Vector2f q = p - origin;
    local.emplace_back(q.dot(table.major_axis), q.dot(table.minor_axis));
  }
  const Eigen::Vector2f minor_range = edgeRange(local, 0, 1);
  const Eigen::Vector2f major_range = edgeRange(local, 1, 0);
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
  table.hull = convexHull2d(hullCandidates(top));
  if (table.hull.size() < 3) {
    outcome.reason = "degenerate cluster of " + std::to_string(n) + " points: its top has no area";
    return outcome;
  }
  outcome.ok = true;
  return outcome;
}

// ---------------------------------------------------------------------------
// Reachability of search positions.

class ReachabilityGrid {
 public:
  ReachabilityGrid(const OrganizedCloud& cloud, const LabelImage& labels,
                   const Eigen::AlignedBox2f& region, const TableConfig& config)
      : config_(config), origin_(region.min()), cell_(config.floor_cell_m) {
    const Eigen::Vector2f size = region.sizes();
    cols_ = static_cast<int>(size.x() / cell_) + 1;
    rows_ = static_cast<int>(size.y() / cell_) + 1;
    const std::size_t cells = static_cast<std::size_t>(cols_) * rows_;
    floor_seen_.assign(cells, 0);
    obstacle_start_.assign(cells + 1, 0);

    std::vector<std::pair<int, Eigen::Vector2f>> obstacles;
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
      const Eigen::Vector3f& p = cloud.points[i];
      if (!finitePoint(p)) continue;
      const int c = cellOf(p.head<2>());
      if (c < 0) continue;
      const std::uint8_t label = labels.labels[i];
      if (label == kFloorLabel) {
        if (std::abs(p.z()) <= config.floor_tolerance_m) floor_seen_[c] = 1;
      } else if (p.z() >= config.obstacle_min_height_m && p.z() <= config.robot_height_m) {
        obstacles.emplace_back(c, p.head<2>());
      }
    }
    for (const auto& [c, xy] : obstacles) ++obstacle_start_[c + 1];
    for (std::size_t c = 0; c < cells; ++c) obstacle_start_[c + 1] += obstacle_start_[c];
    obstacle_points_.resize(obstacles.size());
    std::vector<int> fill(obstacle_start_.begin(), obstacle_start_.end() - 1);
    for (const auto& [c, xy] : obstacles) obstacle_points_[fill[c]++] = xy;
  }

  void assess(SearchPosition& position) const {
    const float r = config_.robot_radius_m;
    const Eigen::Vector2f& q = position.xy;
    int footprint = 0, seen = 0, obstacle_count = 0;
    const int c0 = static_cast<int>(std::floor((q.x() - r - origin_.x()) / cell_));
    const int c1 = static_cast<int>(std::floor((q.x() + r - origin_.x()) / cell_));
    const int r0 = static_cast<int>(std::floor((q.y() - r - origin_.y()) / cell_));
    const int r1 = static_cast<int>(std::floor((q.y() + r - origin_.y()) / cell_));
    const int own = cellOf(q);
    for (int row = std::max(0, r0); row <= std::min(rows_ - 1, r1); ++row) {
      for (int col = std::max(0, c0); col <= std::min(cols_ - 1, c1); ++col) {
        const int c = row * cols_ + col;
        const Eigen::Vector2f centre =
            origin_ + Eigen::Vector2f((col + 0.5f) * cell_, (row + 0.5f) * cell_);
        // Footprint: cells whose centre is under the robot, and always the
        // cell of the position itself (for radii below half a cell).
        if ((centre - q).norm() <= r || c == own) {
          ++footprint;
          seen += floor_seen_[c];
        }
        for (int k = obstacle_start_[c]; k < obstacle_start_[c + 1]; ++k) {
          if ((obstacle_points_[k] - q).squaredNorm() <= r * r) ++obstacle_count;
        }
      }
    }
    std::string reason;
    if (obstacle_count >= config_.obstacle_min_points) {
      reason = "obstacle within robot radius (" + std::to_string(obstacle_count) + " points)";
    }
    const float seen_fraction = footprint > 0 ? static_cast<float>(seen) / footprint : 0.0f;
    if (seen_fraction < config_.min_floor_observed_fraction) {
      if (!reason.empty()) reason += "; ";
      reason += "no observed floor (" + std::to_string(static_cast<int>(100.0f * seen_fraction)) +
                " % of the footprint seen)";
    }
    position.reachable = reason.empty();
    position.reason = reason;
  }

 private:
  int cellOf(const Eigen::Vector2f& xy) const {
    const int col = static_cast<int>(std::floor((xy.x() - origin_.x()) / cell_));
    const int row = static_cast<int>(std::floor((xy.y() - origin_.y()) / cell_));
    if (col < 0 || row < 0 || col >= cols_ || row >= rows_) return -1;
    return row * cols_ + col;
  }

  const TableConfig& config_;
  Eigen::Vector2f origin_;
  float cell_;
  int cols_ = 0, rows_ = 0;
  std::vector<std::uint8_t> floor_seen_;
  std::vector<int> obstacle_start_;
  std::vector<Eigen::Vector2f> obstacle_points_;
};

void checkInputs(const OrganizedCloud& cloud, const LabelImage& labels) {
  const std::size_t pixels = static_cast<std::size_t>(std::max(cloud.width, 0)) *
                             static_cast<std::size_t>(std::max(cloud.height, 0));
  if (cloud.width < 0 || cloud.height < 0 || cloud.points.size() != pixels) {
    throw Error("findTables: cloud is " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height) + " but holds " + std::to_string(cloud.points.size()) +
                " points");
  }
  if (labels.width != cloud.width || labels.height != cloud.height ||
      labels.labels.size() != pixels) {
    throw Error("findTables: label image is " + std::to_string(labels.width) + "x" +
                std::to_string(labels.height) + " with " + std::to_string(labels.labels.size()) +
                " labels, cloud is " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height));
  }
  if (!labels.confidence.empty() && labels.confidence.size() != pixels) {
    throw Error("findTables: label image has " + std::to_string(labels.confidence.size()) +
                " confidence values for " + std::to_string(pixels) + " pixels");
  }
}

}  // namespace

std::vector<int> euclideanClusterLabels(const std::vector<Eigen::Vector3f>& points,
                                        float tolerance) {
  if (!std::isfinite(tolerance) || tolerance < kMinToleranceM) {
    throw Error("euclideanClusterLabels: tolerance " + fmt(tolerance, 6) +
                " must be at least 0.001 m");
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    if (!finitePoint(p) || p.cwiseAbs().maxCoeff() > kMaxPlausibleRangeM) {
      throw Error("euclideanClusterLabels: point " + std::to_string(i) + " (" + fmt(p.x()) + ", " +
                  fmt(p.y()) + ", " + fmt(p.z()) + ") is not finite or beyond 100 m");
    }
  }
  return clusterPoints(points, tolerance);
}

namespace {

// Shortest open path from `start` through all points (Held-Karp dynamic
// programme, O(n^2 2^n)): exact, for the few positions of a frame.
std::vector<int> exactVisitingOrder(const Eigen::Vector2f& start,
                                    const std::vector<Eigen::Vector2f>& points) {
  const int n = static_cast<int>(points.size());
  const std::size_t subsets = std::size_t{1} << n;
  std::vector<float> cost(subsets * n, std::numeric_limits<float>::max());
  std::vector<std::int8_t> previous(subsets * n, -1);
  for (int i = 0; i < n; ++i) cost[(std::size_t{1} << i) * n + i] = (points[i] - start).norm();
  for (std::size_t mask = 1; mask < subsets; ++mask) {
    for (int last = 0; last < n; ++last) {
      const float c = cost[mask * n + last];
      if (!(mask & (std::size_t{1} << last)) || c == std::numeric_limits<float>::max()) continue;
      for (int next = 0; next < n; ++next) {
        if (mask & (std::size_t{1} << next)) continue;
        const std::size_t grown = mask | (std::size_t{1} << next);
        const float candidate = c + (points[next] - points[last]).norm();
        if (candidate < cost[grown * n + next]) {
          cost[grown * n + next] = candidate;
          previous[grown * n + next] = static_cast<std::int8_t>(last);
        }
      }
    }
  }
  std::size_t mask = subsets - 1;
  int last = 0;
  for (int i = 1; i < n; ++i) {
    if (cost[mask * n + i] < cost[mask * n + last]) last = i;
  }
  std::vector<int> order;
  while (last >= 0) {
    order.push_back(last);
    const int before = previous[mask * n + last];
    mask &= ~(std::size_t{1} << last);
    last = before;
  }
  std::reverse(order.begin(), order.end());
  return order;
}

constexpr int kExactVisitingOrderMax = 12;

}  // namespace

std::vector<int> visitingOrder(const Eigen::Vector2f& start,
                               const std::vector<Eigen::Vector2f>& points) {
  const int n = static_cast<int>(points.size());
  if (n == 0) return {};
  if (n <= kExactVisitingOrderMax) return exactVisitingOrder(start, points);
  std::vector<int> order;
  order.reserve(points.size());
  std::vector<bool> used(points.size(), false);
  Eigen::Vector2f at = start;
  for (int step = 0; step < n; ++step) {
    int best = -1;
    float best_d = std::numeric_limits<float>::max();
    for (int i = 0; i < n; ++i) {
      const float d = (points[i] - at).squaredNorm();
      if (!used[i] && d < best_d) {
        best = i;
        best_d = d;
      }
    }
    used[best] = true;
    order.push_back(best);
    at = points[best];
  }
  // 2-opt on the open path start -> order[0] -> ... -> order[n-1]: reversing
  // order[i..j] replaces edges (prev_i, i) and (j, next_j) by (prev_i, j) and
  // (i, next_j); the path has no edge after its last point.
  const auto pointAt = [&](int k) -> const Eigen::Vector2f& {
    return k < 0 ? start : points[order[k]];
  };
  bool improved = true;
  for (int pass = 0; improved && pass < 100; ++pass) {
    improved = false;
    for (int i = 0; i < n - 1; ++i) {
      for (int j = i + 1; j < n; ++j) {
        const float before = (pointAt(i - 1) - pointAt(i)).norm() +
                             (j + 1 < n ? (pointAt(j) - pointAt(j + 1)).norm() : 0.0f);
        const float after = (pointAt(i - 1) - pointAt(j)).norm() +
                            (j + 1 < n ? (pointAt(i) - pointAt(j + 1)).norm() : 0.0f);
        if (after < before - 1e-6f) {
          std::reverse(order.begin() + i, order.begin() + j + 1);
          improved = true;
        }
      }
    }
  }
  return order;
}

std::vector<Eigen::Vector2f> convexHull2d(std::vector<Eigen::Vector2f> points) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) return points;
  // Andrew's monotone chain; popping on cross <= 0 drops collinear points.
  std::vector<Eigen::Vector2f> hull(2 * points.size());
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
  return hull;
}

std::vector<SearchPosition> computeSearchPositions(const TableCluster& table,
                                                   const TableConfig& config) {
  const float d = config.safety_distance_m;
  const float r = config.arm_reach_m;
  const float half_length = table.extents.x();
  const float half_width = table.extents.y();
  int per_side = 1;
  if (r > d) {
    // Half-length of the edge one position covers: up to the midline of the
    // top when the arm gets that far, else the edge strip.
    const float to_midline = d + half_width;
    const float h =
        r > to_midline ? std::sqrt(r * r - to_midline * to_midline) : std::sqrt(r * r - d * d);
    // Guard against absurd counts from a tiny reach margin.
    per_side = std::clamp(static_cast<int>(std::ceil(half_length / h - 1e-4f)), 1, 64);
  }
  std::vector<SearchPosition> positions;
  for (int side : {1, -1}) {
    const Eigen::Vector2f normal = table.minor_axis * static_cast<float>(side);
    const float yaw = std::atan2(-normal.y(), -normal.x());  // facing the table
    for (int k = 0; k < per_side; ++k) {
      SearchPosition p;
      p.side = side;
      p.along_m = half_length * (static_cast<float>(2 * k + 1) / per_side - 1.0f);
      p.xy = table.center + table.major_axis * p.along_m + normal * (half_width + d);
      p.yaw = yaw;
      positions.push_back(p);
    }
  }
  return positions;
}

TableDetection detectTables(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                            const TableConfig& config) {
  validateTableConfig(config);
  TableDetection result;
  if (cloud_ground.points.empty()) {
    result.diagnostics.push_back(
        "no ground-aligned cloud (no ground plane for this frame): no tables");
    return result;
  }
  checkInputs(cloud_ground, labels);

  // 1. Table points.
  std::vector<Eigen::Vector3f> points;
  std::vector<int> pixels;
  for (std::size_t i = 0; i < cloud_ground.points.size(); ++i) {
    if (labels.labels[i] != kTableLabel) continue;
    const Eigen::Vector3f& p = cloud_ground.points[i];
    if (!finitePoint(p)) {
      ++result.nonfinite_points;
      continue;
    }
    if (p.z() < config.min_table_height_m || p.z() > config.max_table_height_m ||
        std::abs(p.x()) > kMaxPlausibleRangeM || std::abs(p.y()) > kMaxPlausibleRangeM) {
      ++result.implausible_points;
      continue;
    }
    points.push_back(p);
    pixels.push_back(static_cast<int>(i));
  }
  result.table_points = static_cast<int>(points.size());
  if (result.nonfinite_points > 0) {
    result.diagnostics.push_back(std::to_string(result.nonfinite_points) +
                                 " table-labelled points with non-finite coordinates ignored");
  }
  if (result.implausible_points > 0) {
    result.diagnostics.push_back(
        std::to_string(result.implausible_points) + " table-labelled points outside [" +
        fmt(config.min_table_height_m) + ", " + fmt(config.max_table_height_m) +
        "] m height (tables.min/max_table_height_m) or beyond 100 m ignored");
  }
  if (points.empty()) {
    result.diagnostics.push_back("no table-labelled points at table height: no tables");
    return result;
  }

  // 2. Clusters.
  const std::vector<int> cluster_of = clusterPoints(points, config.cluster_tolerance_m);
  const int clusters = *std::max_element(cluster_of.begin(), cluster_of.end()) + 1;
  std::vector<std::vector<int>> members(static_cast<std::size_t>(clusters));
  for (int i = 0; i < static_cast<int>(points.size()); ++i) members[cluster_of[i]].push_back(i);

  int small_clusters = 0, largest_small = 0;
  std::vector<TableCluster> tables;
  for (const auto& member : members) {
    const int n = static_cast<int>(member.size());
    if (n < config.min_cluster_points) {
      ++small_clusters;
      largest_small = std::max(largest_small, n);
      continue;
    }
    if (n > config.max_cluster_points) {
      ++result.clusters_rejected;
      result.diagnostics.push_back("cluster of " + std::to_string(n) +
                                   " points above tables.max_cluster_points (" +
                                   std::to_string(config.max_cluster_points) + ") dropped");
      continue;
    }
    // 3. Geometry.
    std::vector<Eigen::Vector3f> cluster_points;
    std::vector<float> confidence;
    cluster_points.reserve(member.size());
    confidence.reserve(member.size());
    for (int i : member) {
      cluster_points.push_back(points[i]);
      // A label image without confidence (ground truth) counts as certain.
      confidence.push_back(labels.confidence.empty() ? 1.0f : labels.confidence[pixels[i]]);
    }
    TableCluster table;
    const ClusterOutcome outcome = describeCluster(cluster_points, confidence, config, table);
    if (!outcome.ok) {
      ++result.clusters_rejected;
      result.diagnostics.push_back(outcome.reason + ": dropped");
      continue;
    }
    table.pixels.reserve(member.size());
    for (int i : member) table.pixels.push_back(pixels[i]);
    std::sort(table.pixels.begin(), table.pixels.end());
    tables.push_back(std::move(table));
  }
  if (small_clusters > 0) {
    result.clusters_rejected += small_clusters;
    result.diagnostics.push_back(
        std::to_string(small_clusters) + " clusters below tables.min_cluster_points (" +
        std::to_string(config.min_cluster_points) + ") dropped, the largest of " +
        std::to_string(largest_small) + " points");
  }
  std::stable_sort(tables.begin(), tables.end(), [](const TableCluster& a, const TableCluster& b) {
    return a.point_count > b.point_count;
  });

  // 4. Search positions, 5. their reachability.
  Eigen::AlignedBox2f region;
  for (std::size_t k = 0; k < tables.size(); ++k) {
    tables[k].id = static_cast<int>(k);
    tables[k].search_positions = computeSearchPositions(tables[k], config);
    for (const auto& p : tables[k].search_positions) region.extend(p.xy);
  }
  if (!tables.empty()) {
    const float margin = config.robot_radius_m + config.floor_cell_m;
    region.extend(region.min() - Eigen::Vector2f::Constant(margin));
    region.extend(region.max() + Eigen::Vector2f::Constant(margin));
    const ReachabilityGrid grid(cloud_ground, labels, region, config);
    for (auto& table : tables) {
      for (auto& position : table.search_positions) grid.assess(position);
    }
  }
  result.tables = std::move(tables);
  return result;
}

std::vector<TableCluster> findTables(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                                     const TableConfig& config) {
  return detectTables(cloud_ground, labels, config).tables;
}

}  // namespace findmug
