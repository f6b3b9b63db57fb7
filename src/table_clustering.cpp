// table_clustering.cpp — exact Euclidean clustering of table points.
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
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>

#include "findmug/error.hpp"
#include "findmug/tables.hpp"
#include "tables_internal.hpp"

namespace findmug {

using namespace tables_detail;

namespace {

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

}  // namespace

std::vector<int> tables_detail::clusterPoints(const std::vector<Eigen::Vector3f>& points, float tolerance) {
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

}  // namespace findmug
