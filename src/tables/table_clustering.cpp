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
// insert per point. The organized grid does not define the neighbourhoods,
// because parts of one table split by an occluder (a chair back, a mug) must
// still join when they are close in 3-D; but when the points come with their
// pixels (detectTables), image neighbours within the tolerance are linked
// first, for free, so that the voxel pass finds almost every neighbouring
// voxel pair already joined and compares few points.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "findmug/common/error.hpp"
#include "findmug/tables/tables.hpp"
#include "tables/tables_internal.hpp"

namespace findmug {

using namespace tables_detail;

namespace {

// Open-addressing hash map from packed voxel keys to dense voxel ids. It
// grows with the number of voxels (kept at most half full), not with the
// number of points: a table top of 100k points has a few thousand voxels,
// and a small table stays in cache for the neighbour lookups.
class VoxelIndex {
 public:
  VoxelIndex() { reset(1024); }
  // Empty again, keeping the table it grew to (a stream of similar frames
  // then inserts without rehashing or allocating).
  void clear() {
    std::fill(keys_.begin(), keys_.end(), kEmpty);
    size_ = 0;
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
        inserted = true;
        if (2 * (size_ + 1) > keys_.size()) {
          grow();
          slot = hash(key);
          while (keys_[slot] != kEmpty) slot = (slot + 1) & mask_;
        }
        keys_[slot] = key;
        values_[slot] = next_id;
        ++size_;
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
    // Fibonacci hashing: the top bits of the product depend on every bit of
    // the key (x, y and z fields alike).
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  void reset(std::size_t capacity) {  // a power of two
    keys_.assign(capacity, kEmpty);
    values_.assign(capacity, -1);
    mask_ = capacity - 1;
    shift_ = 64;
    for (std::size_t c = capacity; c > 1; c >>= 1) --shift_;
  }
  void grow() {
    std::vector<std::uint64_t> keys = std::move(keys_);
    std::vector<int> values = std::move(values_);
    reset(2 * keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (keys[i] == kEmpty) continue;
      std::size_t slot = hash(keys[i]);
      while (keys_[slot] != kEmpty) slot = (slot + 1) & mask_;
      keys_[slot] = keys[i];
      values_[slot] = values[i];
    }
  }
  std::vector<std::uint64_t> keys_;
  std::vector<int> values_;
  std::size_t mask_ = 0;
  int shift_ = 64;
  std::size_t size_ = 0;
};

class DisjointSets {
 public:
  void clear() { parent_.clear(); }
  // A new singleton set; ids are 0, 1, ... in order of addition.
  void add() { parent_.push_back(static_cast<int>(parent_.size())); }
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

// clusterPoints' working memory (see there).
struct ClusterScratch {
  VoxelIndex index;
  DisjointSets sets;
  std::vector<int> point_voxel, voxel_size, start, fill, near_a, near_b, root_label;
  std::vector<int> set_of, index_of_root, near_sets, near_start;
  std::vector<int> run_end, run_voxel;
  std::vector<std::uint8_t> may_link;
  std::vector<Eigen::Vector3i> voxel_coords;
  std::vector<Eigen::AlignedBox3f> boxes, set_boxes;
  std::vector<Eigen::Vector3f> sorted;
};

// Voxels whose points can be within the tolerance are at most this many
// cells apart on each axis: ceil(tolerance / voxel) = ceil(sqrt(3) / 0.999).
constexpr int kReach = 2;

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

// scratch.may_link[v] = 1 when voxel v's box comes within the tolerance (squared:
// tol2) of the box of a set other than its own, in the partition `sets`
// holds now; 0 otherwise (clusterPoints says why such voxels need no look).
// With many sets (fragmented points) every voxel is marked: the test would
// cost more than it saves.
void markVoxelsThatMayLink(DisjointSets& sets, const std::vector<Eigen::AlignedBox3f>& boxes,
                           float tol2, ClusterScratch& scratch) {
  constexpr int kMaxSets = 64;
  std::vector<std::uint8_t>& may_link = scratch.may_link;
  const int voxels = static_cast<int>(boxes.size());
  std::vector<int>& set_of = scratch.set_of;  // dense set index per voxel
  std::vector<int>& index_of_root = scratch.index_of_root;  // dense set index per root, or -1
  index_of_root.assign(static_cast<std::size_t>(voxels), -1);
  set_of.resize(static_cast<std::size_t>(voxels));
  std::vector<Eigen::AlignedBox3f>& set_boxes = scratch.set_boxes;
  set_boxes.clear();
  for (int v = 0; v < voxels; ++v) {
    const int root = sets.find(v);
    if (index_of_root[root] < 0) {
      if (static_cast<int>(set_boxes.size()) == kMaxSets) {
        may_link.assign(static_cast<std::size_t>(voxels), 1);
        return;
      }
      index_of_root[root] = static_cast<int>(set_boxes.size());
      set_boxes.emplace_back();
    }
    set_of[v] = index_of_root[root];
    set_boxes[set_of[v]].extend(boxes[v]);
  }
  // The sets near each set (boxes within the tolerance), as lists.
  const int set_count = static_cast<int>(set_boxes.size());
  std::vector<int>& near_start = scratch.near_start;
  std::vector<int>& near_sets = scratch.near_sets;
  near_start.assign(static_cast<std::size_t>(set_count) + 1, 0);
  near_sets.clear();
  for (int s = 0; s < set_count; ++s) {
    for (int t = 0; t < set_count; ++t) {
      if (t != s && squaredGap(set_boxes[s], set_boxes[t]) <= tol2) near_sets.push_back(t);
    }
    near_start[s + 1] = static_cast<int>(near_sets.size());
  }
  may_link.resize(static_cast<std::size_t>(voxels));
  for (int v = 0; v < voxels; ++v) {
    const int s = set_of[v];
    std::uint8_t mark = 0;
    for (int k = near_start[s]; k < near_start[s + 1] && !mark; ++k) {
      mark = squaredGap(boxes[v], set_boxes[near_sets[k]]) <= tol2 ? 1 : 0;
    }
    may_link[v] = mark;
  }
}

// clusterPoints' first pass, over the points in order: the voxel of each
// point (scratch.point_voxel), each voxel's cell, bounding box and point
// count, one set per voxel (scratch.sets), the runs of consecutive points in
// one voxel (scratch.run_end, run_voxel: the passes after this one go run by
// run instead of point by point), and, when the points come with their pixels
// (`pixels`, checked against `grid`), the links between image neighbours.
// Inlined into its one caller: as a function of its own, the clustering ran 2 %
// more instructions (callgrind, frame_cpu over the NYU frames).
__attribute__((always_inline)) inline void voxelizeAndLinkImageNeighbours(
    const std::vector<Eigen::Vector3f>& points, const std::vector<int>* pixels,
    const PointGrid& grid, float voxel, float tol2, ClusterScratch& scratch) {
  const int n = static_cast<int>(points.size());
  // Pixel offsets of a point's grid neighbours: left and above.
  const int step_x = pixels ? grid.stride : 0;
  const int step_y = pixels ? grid.stride * grid.width : 0;
  VoxelIndex& index = scratch.index;
  index.clear();
  std::vector<int>& point_voxel = scratch.point_voxel;
  point_voxel.resize(points.size());
  std::vector<Eigen::Vector3i>& voxel_coords = scratch.voxel_coords;
  voxel_coords.clear();
  std::vector<Eigen::AlignedBox3f>& boxes = scratch.boxes;
  boxes.clear();
  std::vector<int>& voxel_size = scratch.voxel_size;
  voxel_size.clear();
  DisjointSets& sets = scratch.sets;
  sets.clear();
  const float inv_voxel = 1.0f / voxel;
  std::uint64_t last_key = ~std::uint64_t{0};
  int last_voxel = -1;
  // The current run of consecutive points in one voxel keeps its box and
  // count here, in registers, and adds them to the voxel's when the run
  // ends: updating boxes[v] and voxel_size[v] in memory point by point
  // made every point wait for the previous point's store. Folding a run's
  // box into the voxel's keeps each coordinate's minimum and maximum (and
  // which of equal values, as Eigen's extend keeps the earlier one).
  // The runs are also listed (where each ends, and its voxel): the passes
  // after this one go run by run instead of point by point.
  Eigen::AlignedBox3f run_box;
  int run_size = 0;
  std::vector<int>& run_end = scratch.run_end;
  std::vector<int>& run_voxel = scratch.run_voxel;
  run_end.clear();
  run_voxel.clear();
  const auto endRun = [&](int end) {
    if (run_size == 0) return;
    boxes[last_voxel].extend(run_box);
    voxel_size[last_voxel] += run_size;
    run_end.push_back(end);
    run_voxel.push_back(last_voxel);
    run_box.setEmpty();
    run_size = 0;
  };
  int joined_above = -1, joined_below = -1;  // the last voxels an upper link joined
  int up = 0;       // first point whose pixel is not before the one above point i's
  int row_end = 0;  // end of the image row of point i's pixel (kept up to date at run starts)
  // Voxel coordinates kBlock points at a time: split into x, y, z arrays,
  // then a loop the compiler makes four wide (the same products and floors
  // as point by point).
  constexpr int kBlock = 256;
  alignas(16) float coord[3][kBlock];
  alignas(16) int cell[3][kBlock];
  for (int i = 0; i < n; ++i) {
    const int j = i % kBlock;
    if (j == 0) {
      const int m = std::min(kBlock, n - i);
      for (int k = 0; k < m; ++k) {
        for (int axis = 0; axis < 3; ++axis) coord[axis][k] = points[i + k][axis];
      }
      for (int axis = 0; axis < 3; ++axis) {
        for (int k = 0; k < m; ++k) cell[axis][k] = floorToInt(coord[axis][k] * inv_voxel);
      }
    }
    const Eigen::Vector3f& p = points[i];
    const Eigen::Vector3i c(cell[0][j], cell[1][j], cell[2][j]);
    const std::uint64_t key = packVoxel(c.x(), c.y(), c.z());
    // Points come in image order, so neighbours often share a voxel: the
    // previous point's (last_key), or the one above's.
    const bool new_run = key != last_key;
    if (new_run) {
      endRun(i);
      if (pixels) {
        const int above = (*pixels)[i] - step_y;
        while (up < i && (*pixels)[up] < above) ++up;
        if (up < i && (*pixels)[up] == above && voxel_coords[point_voxel[up]] == c) {
          last_voxel = point_voxel[up];
          last_key = key;
        }
      }
      if (key != last_key) {
        bool inserted = false;
        last_voxel = index.findOrInsert(key, static_cast<int>(voxel_coords.size()), inserted);
        last_key = key;
        if (inserted) {
          voxel_coords.push_back(c);
          boxes.emplace_back();
          voxel_size.push_back(0);
          sets.add();
        }
      }
    }
    point_voxel[i] = last_voxel;
    run_box.extend(p);
    ++run_size;
    if (pixels) {
      // Image neighbours (left, above) within the tolerance are links of the
      // exact partition found without any search; on a table top they join
      // almost every pair of neighbouring voxels, so the voxel pass
      // (joinNeighbouringVoxels) rarely has to compare points.
      const int px = (*pixels)[i];
      // The left neighbour is the previous point (when its pixel is): in
      // the same voxel, hence linked already, unless a new run starts here.
      if (new_run && i > 0) {
        while (px >= row_end) row_end += grid.width;  // pixels ascend: no division
        if ((*pixels)[i - 1] == px - step_x && px - step_x >= row_end - grid.width &&
            (points[i - 1] - p).squaredNorm() <= tol2) {
          sets.unite(point_voxel[i - 1], last_voxel);
        }
      }
      const int above = px - step_y;
      while (up < i && (*pixels)[up] < above) ++up;
      // Along a row the points of one voxel often have their upper
      // neighbours in one other voxel: once that pair is joined, the next
      // points of the run need neither the distance nor the join (joining
      // twice changes nothing).
      if (up < i && (*pixels)[up] == above && point_voxel[up] != last_voxel &&
          (point_voxel[up] != joined_above || last_voxel != joined_below) &&
          (points[up] - p).squaredNorm() <= tol2) {
        sets.unite(point_voxel[up], last_voxel);
        joined_above = point_voxel[up];
        joined_below = last_voxel;
      }
    }
  }
  endRun(n);
}

// The points of the voxels marked in scratch.may_link, grouped by voxel
// (a counting sort into scratch.sorted; voxel v's points at
// sorted[start[v] .. start[v + 1])), for the pair tests of
// joinNeighbouringVoxels. Built only when a pair of voxels has to be decided
// point by point: the pair tests then read memory sequentially. Only the
// points of marked voxels are grouped: both voxels of a pair tested point by
// point are marked (a pair of different sets whose boxes come within the
// tolerance now was such a pair when the marks were made, as sets only merge
// and a set's box holds its voxels'), and on a table top they are a few per
// cent of the points, where copying all of them cost more than all the tests.
void groupMarkedPointsByVoxel(const std::vector<Eigen::Vector3f>& points, ClusterScratch& scratch) {
  const int voxels = static_cast<int>(scratch.voxel_coords.size());
  const int runs = static_cast<int>(scratch.run_end.size());
  const std::vector<std::uint8_t>& may_link = scratch.may_link;
  const std::vector<int>& voxel_size = scratch.voxel_size;
  const std::vector<int>& run_end = scratch.run_end;
  const std::vector<int>& run_voxel = scratch.run_voxel;
  std::vector<int>& start = scratch.start;
  std::vector<Eigen::Vector3f>& sorted = scratch.sorted;
  start.assign(static_cast<std::size_t>(voxels) + 1, 0);
  for (int v = 0; v < voxels; ++v) start[v + 1] = start[v] + (may_link[v] ? voxel_size[v] : 0);
  std::vector<int>& fill = scratch.fill;
  fill.assign(start.begin(), start.end() - 1);
  sorted.resize(static_cast<std::size_t>(start[voxels]));
  // By the runs of the first pass: one counter update per run, not a
  // chain of read-modify-writes of the same counter.
  for (int r = 0, begin = 0; r < runs; begin = run_end[r++]) {
    const int v = run_voxel[r];
    if (may_link[v]) {
      std::copy(points.begin() + begin, points.begin() + run_end[r], sorted.begin() + fill[v]);
      fill[v] += run_end[r] - begin;
    }
  }
}

// The voxel pass: joins the sets of neighbouring voxels (up to kReach cells
// apart) that hold a pair of points within the tolerance, testing only
// voxels that may link to another set (markVoxelsThatMayLink) and pairs not
// joined already whose boxes come within the tolerance.
void joinNeighbouringVoxels(const std::vector<Eigen::Vector3f>& points, float voxel, float tol2,
                            ClusterScratch& scratch) {
  const int voxels = static_cast<int>(scratch.voxel_coords.size());
  const VoxelIndex& index = scratch.index;
  DisjointSets& sets = scratch.sets;
  const std::vector<Eigen::Vector3i>& voxel_coords = scratch.voxel_coords;
  const std::vector<Eigen::AlignedBox3f>& boxes = scratch.boxes;
  const std::vector<std::uint8_t>& may_link = scratch.may_link;
  const std::vector<int>& start = scratch.start;
  const std::vector<Eigen::Vector3f>& sorted = scratch.sorted;
  bool grouped = false;  // groupMarkedPointsByVoxel has run
  // A lower bound of the gap between voxel a's points and any point of the
  // voxel at offset d: the distance from a's box to that voxel's cell, the
  // root of the sum over the axes of gap[axis][d[axis]] (squared gaps to the
  // cells `d` steps away along one axis, 0 for d = 0). Most voxels' points
  // stay clear of most of their cell's faces (a table top is a thin layer),
  // so most offsets are ruled out before the hash lookup, and whole planes
  // of them (dz, then dz and dy) at once: a partial sum of the non-negative
  // squared gaps never exceeds the full one, rounding included. The slack
  // covers the rounding of floor(p / voxel) at cell borders.
  const float slack = 1e-4f;
  float gap_store[3][2 * kReach + 1];
  const auto gapsOf = [&](const Eigen::AlignedBox3f& box, const Eigen::Vector3i& ca) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int d = -kReach; d <= kReach; ++d) {
        float g = 0.0f;
        if (d > 0) {
          g = static_cast<float>(ca[axis] + d) * voxel - box.max()[axis] - slack;
        } else if (d < 0) {
          g = box.min()[axis] - static_cast<float>(ca[axis] + d + 1) * voxel - slack;
        }
        gap_store[axis][d + kReach] = g > 0.0f ? g * g : 0.0f;
      }
    }
  };
  const auto gap = [&](int axis, int d) { return gap_store[axis][d + kReach]; };

  // Each unordered voxel pair once (the forward half of the neighbourhood),
  // the touching voxels (ring 1) of every voxel first: on a dense surface
  // they join nearly everything, so the farther pairs are then mostly
  // skipped as already joined.
  std::vector<int>& near_a = scratch.near_a;
  std::vector<int>& near_b = scratch.near_b;
  const auto tryPair = [&](int a, const Eigen::Vector3i& ca, int dx, int dy, int dz) {
    const int b = index.find(packVoxel(static_cast<std::int64_t>(ca.x()) + dx,
                                       static_cast<std::int64_t>(ca.y()) + dy,
                                       static_cast<std::int64_t>(ca.z()) + dz));
    if (b < 0 || sets.find(a) == sets.find(b)) return;
    if (squaredGap(boxes[a], boxes[b]) > tol2) return;
    if (!grouped) {
      groupMarkedPointsByVoxel(points, scratch);
      grouped = true;
    }
    // Only points within the tolerance of the other voxel's box can link.
    near_a.clear();
    near_b.clear();
    for (int k = start[a]; k < start[a + 1]; ++k) {
      if (boxes[b].squaredExteriorDistance(sorted[k]) <= tol2) near_a.push_back(k);
    }
    if (near_a.empty()) return;
    for (int k = start[b]; k < start[b + 1]; ++k) {
      if (boxes[a].squaredExteriorDistance(sorted[k]) <= tol2) near_b.push_back(k);
    }
    for (const int ka : near_a) {
      const Eigen::Vector3f& p = sorted[ka];
      for (const int kb : near_b) {
        if ((sorted[kb] - p).squaredNorm() <= tol2) {
          sets.unite(a, b);
          return;
        }
      }
    }
  };
  for (int ring = 1; ring <= kReach; ++ring) {
    for (int a = 0; a < voxels; ++a) {
      if (!may_link[a]) continue;
      const Eigen::Vector3i& ca = voxel_coords[a];
      gapsOf(boxes[a], ca);
      for (int dz = 0; dz <= ring; ++dz) {  // forward: dz > 0, or dz == 0 and ...
        const float gz = gap(2, dz);
        if (gz > tol2) continue;
        for (int dy = dz > 0 ? -ring : 0; dy <= ring; ++dy) {  // ... dy > 0, or dy == 0 and ...
          if (gz + gap(1, dy) > tol2) continue;
          for (int dx = dz > 0 || dy > 0 ? -ring : 1; dx <= ring; ++dx) {  // ... dx > 0
            if (std::max({std::abs(dx), std::abs(dy), dz}) != ring) continue;
            // Summed in the order x, y, z.
            if ((gap(0, dx) + gap(1, dy)) + gz > tol2) continue;
            tryPair(a, ca, dx, dy, dz);
          }
        }
      }
    }
  }
}

// Dense cluster ids in order of first appearance, written run by run.
void labelRunsByCluster(ClusterScratch& scratch, std::vector<int>& labels) {
  const int voxels = static_cast<int>(scratch.voxel_coords.size());
  const int runs = static_cast<int>(scratch.run_end.size());
  DisjointSets& sets = scratch.sets;
  const std::vector<int>& run_end = scratch.run_end;
  const std::vector<int>& run_voxel = scratch.run_voxel;
  std::vector<int>& root_label = scratch.root_label;
  root_label.assign(static_cast<std::size_t>(voxels), -1);
  int next = 0;
  for (int r = 0, begin = 0; r < runs; begin = run_end[r++]) {
    const int root = sets.find(run_voxel[r]);
    if (root_label[root] < 0) root_label[root] = next++;
    std::fill(labels.begin() + begin, labels.begin() + run_end[r], root_label[root]);
  }
}

}  // namespace

std::vector<int> tables_detail::clusterPoints(const std::vector<Eigen::Vector3f>& points,
                                              float tolerance, const PointGrid& grid) {
  std::vector<int> labels;
  clusterPointsInto(points, tolerance, grid, labels);
  return labels;
}

void tables_detail::clusterPointsInto(const std::vector<Eigen::Vector3f>& points, float tolerance,
                                      const PointGrid& grid, std::vector<int>& labels) {
  const int n = static_cast<int>(points.size());
  labels.resize(points.size());  // every entry is written at the end (runs cover all points)
  if (n == 0) return;
  // Working memory kept per thread: the table stage runs once per frame, and
  // in a stream its buffers settle at the size of the largest table seen.
  thread_local ClusterScratch scratch_tls;
  ClusterScratch& scratch = scratch_tls;
  const std::vector<int>* pixels = grid.pixels;
  if (pixels && (pixels->size() != points.size() || grid.width < 1 || grid.stride < 1)) {
    pixels = nullptr;
  }
  // Slightly under tolerance/sqrt(3) so the voxel diagonal never exceeds the
  // tolerance through rounding; then neighbours within the tolerance are at
  // most kReach voxels away on each axis.
  // With tolerance >= kMinToleranceM and points within kMaxPlausibleRangeM,
  // voxel indices stay well inside their 21-bit fields.
  const float voxel = tolerance / std::sqrt(3.0f) * 0.999f;
  const float tol2 = tolerance * tolerance;

  voxelizeAndLinkImageNeighbours(points, pixels, grid, voxel, tol2, scratch);
  // Voxels that cannot link to another set. After the first pass the image
  // links have joined most voxels (a table top is usually one set, or a few
  // far apart), yet the voxel pass would still look up every neighbour of
  // every voxel only to find it joined already. A voxel whose box is farther
  // than the tolerance from the box of every other set (of the partition so
  // far) needs no look: each pair it would test is joined already, or its
  // boxes are farther apart than the tolerance (a set's box holds its
  // voxels' boxes, and the squared gap only shrinks as a box grows, in
  // floats too), and then the pair test returns without a change. Skipping
  // them leaves the partition, and so the labels, as they are.
  markVoxelsThatMayLink(scratch.sets, scratch.boxes, tol2, scratch);
  joinNeighbouringVoxels(points, voxel, tol2, scratch);
  labelRunsByCluster(scratch, labels);
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
