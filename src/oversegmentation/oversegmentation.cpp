// Oversegmentation stage: the factory, the shared finalisation (drop small
// patches, renumber, adjacency) and the quality measures against ground truth.
// The two oversegmenters live in oversegmentation_pcl.cpp and oversegmentation_organized.cpp.
#include "findmug/oversegmentation/oversegmentation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "findmug/common/error.hpp"
#include "findmug/labels/labels.hpp"
#include "common/int_runs.hpp"
#include "oversegmentation/oversegmentation_internal.hpp"

namespace findmug {

namespace {

std::string fieldError(const std::string& field, const std::string& value,
                       const std::string& expected) {
  return "oversegmentation config: oversegmentation." + field + " = " + value + " (expected " +
         expected + ")";
}

void requireFinitePositive(float value, const char* field) {
  if (!(std::isfinite(value) && value > 0.0f)) {
    throw Error(fieldError(field, std::to_string(value), "a finite value > 0"));
  }
}

void requireFiniteNonNegative(float value, const char* field) {
  if (!(std::isfinite(value) && value >= 0.0f)) {
    throw Error(fieldError(field, std::to_string(value), "a finite value >= 0"));
  }
}

void requireIntRange(int value, int lo, int hi, const char* field) {
  if (value < lo || value > hi) {
    throw Error(
        fieldError(field, std::to_string(value), std::to_string(lo) + ".." + std::to_string(hi)));
  }
}

// Edges (a, b) with a < b, sorted, each once.
void sortUniqueEdges(std::vector<std::pair<int, int>>& edges) {
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
}

}  // namespace

void validateOversegmentationConfig(const OversegmentationConfig& c) {
  if (c.kind != OversegmenterKind::PclSupervoxels && c.kind != OversegmenterKind::Organized) {
    throw Error(fieldError("kind", std::to_string(static_cast<int>(c.kind)), "pcl or organized"));
  }
  requireFinitePositive(c.voxel_resolution_m, "voxel_resolution_m");
  requireFinitePositive(c.seed_resolution_m, "seed_resolution_m");
  if (c.seed_resolution_m <= c.voxel_resolution_m) {
    throw Error(fieldError(
        "seed_resolution_m", std::to_string(c.seed_resolution_m),
        "more than oversegmentation.voxel_resolution_m = " + std::to_string(c.voxel_resolution_m)));
  }
  if (c.seed_resolution_m > 100.0f) {
    throw Error(fieldError("seed_resolution_m", std::to_string(c.seed_resolution_m), "<= 100 m"));
  }
  requireFiniteNonNegative(c.color_importance, "color_importance");
  requireFiniteNonNegative(c.spatial_importance, "spatial_importance");
  requireFiniteNonNegative(c.normal_importance, "normal_importance");
  if (c.color_importance + c.spatial_importance + c.normal_importance <= 0.0f) {
    throw Error(fieldError("color_importance/spatial_importance/normal_importance", "all 0",
                           "at least one > 0"));
  }
  requireIntRange(c.min_segment_points, 0, 1000000, "min_segment_points");
  requireIntRange(c.max_iterations, 1, 100, "max_iterations");
  requireIntRange(c.search_window_factor, 1, 10, "search_window_factor");
  requireFinitePositive(c.organized_seed_density, "organized_seed_density");
  if (c.organized_seed_density > 1000.0f) {
    throw Error(
        fieldError("organized_seed_density", std::to_string(c.organized_seed_density), "<= 1000"));
  }
}

namespace detail {

void checkOversegmentationInput(const OrganizedCloud& cloud, const NormalImage& normals,
                                const char* who) {
  // The message prefix is built only on failure: this runs once per frame.
  const auto prefix = [who] { return std::string(who) + ": "; };
  if (cloud.width <= 0 || cloud.height <= 0 || cloud.width > 100000 || cloud.height > 100000) {
    throw Error(prefix() + "cloud size " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height) + " is not a valid organized grid");
  }
  const std::size_t n = static_cast<std::size_t>(cloud.width) * cloud.height;
  if (cloud.points.size() != n || cloud.colors.size() != n) {
    throw Error(prefix() + "cloud " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height) + " has " + std::to_string(cloud.points.size()) +
                " points and " + std::to_string(cloud.colors.size()) + " colours");
  }
  if (normals.width != cloud.width || normals.height != cloud.height ||
      normals.normals.size() != n) {
    throw Error(prefix() + "normal image " + std::to_string(normals.width) + "x" +
                std::to_string(normals.height) + " with " + std::to_string(normals.normals.size()) +
                " normals does not match the cloud " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height));
  }
}

}  // namespace detail

std::unique_ptr<Oversegmenter> makeOversegmenter(const OversegmentationConfig& config) {
  validateOversegmentationConfig(config);
  switch (config.kind) {
    case OversegmenterKind::PclSupervoxels:
      return detail::makePclSupervoxelOversegmenter(config);
    case OversegmenterKind::Organized:
      return detail::makeOrganizedOversegmenter(config);
  }
  throw Error("makeOversegmenter: unknown oversegmenter kind " +
              std::to_string(static_cast<int>(config.kind)));
}

namespace {

// Pixel lists kept per thread for frames with more segments than the last
// (a VGA frame has about 1500); more are freed.
constexpr std::size_t kMaxSpareLists = 8192;

// The pixel count of `seg`'s grid, after checking the grid and min_points.
std::size_t checkFinalizeInput(const Oversegmentation& seg, int min_points) {
  if (seg.width < 0 || seg.height < 0 || seg.width > 100000 || seg.height > 100000) {
    throw Error("finalizeOversegmentation: grid size " + std::to_string(seg.width) + "x" +
                std::to_string(seg.height) + " is invalid");
  }
  const std::size_t n = static_cast<std::size_t>(seg.width) * seg.height;
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw Error("finalizeOversegmentation: grid " + std::to_string(seg.width) + "x" +
                std::to_string(seg.height) + " has " + std::to_string(n) +
                " pixels, more than an int pixel index holds");
  }
  if (seg.pixel_segment.size() != n) {
    throw Error("finalizeOversegmentation: pixel_segment has " +
                std::to_string(seg.pixel_segment.size()) + " entries, grid " +
                std::to_string(seg.width) + "x" + std::to_string(seg.height) + " needs " +
                std::to_string(n));
  }
  if (min_points < 0) {
    throw Error("finalizeOversegmentation: min_points = " + std::to_string(min_points) +
                " (expected >= 0)");
  }
  return n;
}

// The largest of the n segment ids (-1 when there is none), after checking
// that each is in -1..n-1: ids are bounded by the pixel count so that the
// dense tables indexed by them stay small. The range check is a plain
// minimum and maximum (a loop the compiler vectorises); only a bad image is
// walked again, to name its first bad pixel.
int checkedMaxId(const int* ids, std::size_t n) {
  int min_id = -1, max_id = -1;
  for (std::size_t i = 0; i < n; ++i) {
    min_id = std::min(min_id, ids[i]);
    max_id = std::max(max_id, ids[i]);
  }
  if (min_id < -1 || (max_id >= 0 && static_cast<std::size_t>(max_id) >= n)) {
    for (std::size_t i = 0; i < n; ++i) {
      const int id = ids[i];
      if (id < -1 || (id >= 0 && static_cast<std::size_t>(id) >= n)) {
        throw Error("finalizeOversegmentation: pixel " + std::to_string(i) + " has segment id " +
                    std::to_string(id) + ", outside -1.." + std::to_string(n - 1));
      }
    }
  }
  return max_id;
}

// Pixel count per id (`counts`, ids 0..max_id), counted per run of one id
// (a segment crosses a row in one or two); the runs' starts, then n, go to
// `run_start` for the renumbering pass. Pixel by pixel, each count waited
// for the previous pixel's store to the same counter.
void countPixelsByRun(const int* ids, std::size_t n, int max_id, std::vector<int>& counts,
                      std::vector<int>& run_start) {
  counts.assign(static_cast<std::size_t>(max_id + 1), 0);
  run_start.clear();  // n fits an int (checkFinalizeInput)
  for (std::size_t i = 0; i < n;) {
    const int id = ids[i];
    const std::size_t end = detail::intRunEnd(ids, i, n);
    if (id >= 0) counts[id] += static_cast<int>(end - i);
    run_start.push_back(static_cast<int>(i));
    i = end;
  }
  run_start.push_back(static_cast<int>(n));
}

// Dense renumbering in increasing id order (`remap`); segments below the
// threshold (and ids without pixels) map to -1. Returns how many are kept.
int renumberKeptSegments(const std::vector<int>& counts, int min_points, std::vector<int>& remap) {
  const int keep_at_least = std::max(min_points, 1);
  remap.assign(counts.size(), -1);
  int next = 0;
  for (std::size_t id = 0; id < counts.size(); ++id) {
    if (counts[id] >= keep_at_least) remap[id] = next++;
  }
  return next;
}

// seg.segments becomes `count` lists, largest capacity first. Not assign():
// a recycled `seg` keeps the capacity of its pixel lists (one allocation per
// segment and frame otherwise). Lists beyond this frame's count wait in a
// per-thread spare pool for a frame with more; the smallest go first.
void resizeSegmentLists(Oversegmentation& seg, int count) {
  thread_local std::vector<std::vector<int>> spare_lists_tls;
  std::vector<std::vector<int>>& spare_lists = spare_lists_tls;
  const auto by_capacity = [](const std::vector<int>& a, const std::vector<int>& b) {
    return a.capacity() > b.capacity();
  };
  std::sort(seg.segments.begin(), seg.segments.end(), by_capacity);
  while (seg.segments.size() > static_cast<std::size_t>(count)) {
    if (spare_lists.size() < kMaxSpareLists) spare_lists.push_back(std::move(seg.segments.back()));
    seg.segments.pop_back();  // the smallest go first
  }
  while (seg.segments.size() < static_cast<std::size_t>(count)) {
    if (spare_lists.empty()) {
      seg.segments.emplace_back();
    } else {
      seg.segments.push_back(std::move(spare_lists.back()));
      spare_lists.pop_back();
    }
  }
  std::sort(seg.segments.begin(), seg.segments.end(), by_capacity);
}

// The largest lists (seg.segments, largest capacity first) go to the
// largest segments: list r to the new id of rank r, by decreasing pixel
// count (ties by id, so the order is fixed). Handed out in any order, every
// list would in time grow to fit the largest segment it ever met (lists only
// grow), and the memory of a long stream with it: the 2026-11-25 soak saw
// the heap in use climb 10 MB a minute that way. By rank, the k-th largest
// list only grows to the k-th largest segment ever seen, which is bounded by
// the frame's size over k.
void giveLargestListsToLargestSegments(Oversegmentation& seg, const std::vector<int>& counts,
                                       const std::vector<int>& remap, int kept) {
  thread_local std::vector<int> rank_order_tls;
  thread_local std::vector<std::vector<int>> ranked_tls;
  std::vector<int>& rank_order = rank_order_tls;
  std::vector<std::vector<int>>& ranked = ranked_tls;
  rank_order.clear();
  for (std::size_t id = 0; id < counts.size(); ++id) {
    if (remap[id] >= 0) rank_order.push_back(static_cast<int>(id));
  }
  std::stable_sort(rank_order.begin(), rank_order.end(),
                   [&counts](int a, int b) { return counts[a] > counts[b]; });
  ranked.resize(static_cast<std::size_t>(kept));
  for (std::size_t r = 0; r < rank_order.size(); ++r)
    ranked[static_cast<std::size_t>(remap[rank_order[r]])] = std::move(seg.segments[r]);
  seg.segments.swap(ranked);  // `ranked` keeps the moved-from shells for next time
}

// The runs of countPixelsByRun renumbered in seg.pixel_segment, and each
// kept segment's pixels listed in seg.segments (one list per new id).
void listPixelsOfSegments(Oversegmentation& seg, const std::vector<int>& counts,
                          const std::vector<int>& remap, const std::vector<int>& run_start,
                          int kept) {
  // Each list is sized to its count first and written through a cursor:
  // push_back per pixel reloaded and stored the list's end every time.
  thread_local std::vector<int*> cursor_tls;
  std::vector<int*>& cursor = cursor_tls;
  cursor.resize(static_cast<std::size_t>(kept));
  for (auto& pixels : seg.segments) pixels.clear();
  for (std::size_t id = 0; id < counts.size(); ++id) {
    if (remap[id] < 0) continue;
    std::vector<int>& pixels = seg.segments[remap[id]];
    const auto count = static_cast<std::size_t>(counts[id]);
    // A recycled list that is too small grows with a quarter to spare, so
    // that over a stream the lists settle at sizes that fit every frame.
    if (pixels.capacity() < count)
      pixels.reserve(pixels.capacity() == 0 ? count : count + count / 4);
    pixels.resize(count);
    cursor[static_cast<std::size_t>(remap[id])] = pixels.data();
  }
  for (std::size_t r = 0; r + 1 < run_start.size(); ++r) {
    const auto i = static_cast<std::size_t>(run_start[r]);
    const auto end = static_cast<std::size_t>(run_start[r + 1]);
    const int old_id = seg.pixel_segment[i];
    const int id = old_id >= 0 ? remap[old_id] : old_id;
    if (old_id >= 0) std::fill(seg.pixel_segment.begin() + i, seg.pixel_segment.begin() + end, id);
    if (id >= 0) {
      int*& out = cursor[static_cast<std::size_t>(id)];
      for (std::size_t j = i; j < end; ++j) *out++ = static_cast<int>(j);
    }
  }
}

// EdgeSource::Keep: the input edges (seg.edges, ids of n pixels) in the new
// ids, those of dropped segments left out; sorted, each once.
std::vector<std::pair<int, int>> renumberedKeptEdges(const Oversegmentation& seg,
                                                     const std::vector<int>& remap, int max_id,
                                                     std::size_t n) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(seg.edges.size());
  for (const auto& [a, b] : seg.edges) {
    for (const int id : {a, b}) {
      if (id < 0 || static_cast<std::size_t>(id) >= n) {
        throw Error("finalizeOversegmentation: edge (" + std::to_string(a) + ", " +
                    std::to_string(b) + ") names segment id " + std::to_string(id) +
                    ", outside 0.." + std::to_string(n - 1));
      }
    }
    // Ids beyond max_id have no pixels: such a segment is dropped.
    const int ra = a <= max_id ? remap[a] : -1;
    const int rb = b <= max_id ? remap[b] : -1;
    if (ra < 0 || rb < 0 || ra == rb) continue;
    edges.emplace_back(std::min(ra, rb), std::max(ra, rb));
  }
  sortUniqueEdges(edges);
  return edges;
}

// EdgeSource::Grid: the pairs of segments (of `segments`, ids in the w x h
// image `pixel_segment`) that touch left-right or up-down, sorted, each once,
// into `edges` (its capacity is reused).
void listGridEdges(const std::vector<int>& pixel_segment, int w, int h, int segments,
                   std::vector<std::pair<int, int>>& edges) {
  // Neighbour lists (a segment has a handful) instead of sorting every
  // boundary pixel pair.
  // Per-thread and kept between calls: the lists keep their capacity, so a
  // frame's ~1500 segments cost no allocation once warm.
  thread_local std::vector<std::vector<int>> neighbours_tls;
  std::vector<std::vector<int>>& neighbours = neighbours_tls;
  if (neighbours.size() < static_cast<std::size_t>(segments)) neighbours.resize(segments);
  for (int a = 0; a < segments; ++a) neighbours[a].clear();
  int last_a = -1, last_b = -1;
  const auto add = [&](int a, int b) {
    if (a < 0 || b < 0 || a == b) return;
    if (a > b) std::swap(a, b);
    if (a == last_a && b == last_b) return;  // boundaries run along rows
    last_a = a;
    last_b = b;
    std::vector<int>& list = neighbours[a];
    if (std::find(list.begin(), list.end(), b) == list.end()) list.push_back(b);
  };
  for (int y = 0; y < h; ++y) {
    const int* row = pixel_segment.data() + static_cast<std::size_t>(y) * w;
    const int* below = y + 1 < h ? row + w : nullptr;
    int x = 0;
#if defined(__SSE2__)
    // Most pixels equal their right and lower neighbours: four at a time,
    // and only a group with a boundary goes pixel by pixel (in the same
    // order, so the same calls to add()).
    if (below) {
      for (; x + 5 <= w; x += 4) {
        const __m128i here = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
        const __m128i right = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x + 1));
        const __m128i under = _mm_loadu_si128(reinterpret_cast<const __m128i*>(below + x));
        const __m128i same =
            _mm_and_si128(_mm_cmpeq_epi32(here, right), _mm_cmpeq_epi32(here, under));
        if (_mm_movemask_epi8(same) == 0xffff) continue;
        // The loop below's body, written out (k + 1 < w holds here): a
        // lambda shared by both made the oversegmenter 1.03 of itself.
        for (int k = x; k < x + 4; ++k) {
          if (row[k] != row[k + 1]) add(row[k], row[k + 1]);
          if (row[k] != below[k]) add(row[k], below[k]);
        }
      }
    }
#endif
    for (; x < w; ++x) {
      if (x + 1 < w && row[x] != row[x + 1]) add(row[x], row[x + 1]);
      if (below && row[x] != below[x]) add(row[x], below[x]);
    }
  }
  std::size_t edge_count = 0;
  for (int a = 0; a < segments; ++a) edge_count += neighbours[a].size();
  edges.clear();
  edges.reserve(edge_count);
  for (int a = 0; a < segments; ++a) {
    std::sort(neighbours[a].begin(), neighbours[a].end());
    for (const int b : neighbours[a]) edges.emplace_back(a, b);
  }
}

}  // namespace

void finalizeOversegmentation(Oversegmentation& seg, int min_points, EdgeSource edge_source) {
  const std::size_t n = checkFinalizeInput(seg, min_points);
  const int max_id = checkedMaxId(seg.pixel_segment.data(), n);
  thread_local std::vector<int> counts_tls, remap_tls, run_start_tls;
  std::vector<int>& counts = counts_tls;
  std::vector<int>& remap = remap_tls;
  std::vector<int>& run_start = run_start_tls;
  countPixelsByRun(seg.pixel_segment.data(), n, max_id, counts, run_start);
  const int kept = renumberKeptSegments(counts, min_points, remap);
  resizeSegmentLists(seg, kept);
  giveLargestListsToLargestSegments(seg, counts, remap, kept);
  listPixelsOfSegments(seg, counts, remap, run_start, kept);
  if (edge_source == EdgeSource::Keep) {
    seg.edges = renumberedKeptEdges(seg, remap, max_id, n);
  } else {
    // Written into seg.edges itself: its capacity is reused.
    listGridEdges(seg.pixel_segment, seg.width, seg.height, kept, seg.edges);
  }
}

OversegmentationQuality evaluateOversegmentation(const Oversegmentation& seg,
                                                 const std::vector<std::uint8_t>& gt_labels,
                                                 int tolerance_px) {
  const int w = seg.width;
  const int h = seg.height;
  const std::size_t n = static_cast<std::size_t>(std::max(w, 0)) * std::max(h, 0);
  if (w <= 0 || h <= 0 || seg.pixel_segment.size() != n) {
    throw Error("evaluateOversegmentation: segmentation " + std::to_string(w) + "x" +
                std::to_string(h) + " with " + std::to_string(seg.pixel_segment.size()) +
                " pixel ids is not a valid grid");
  }
  if (gt_labels.size() != n) {
    throw Error("evaluateOversegmentation: ground truth has " + std::to_string(gt_labels.size()) +
                " labels, the " + std::to_string(w) + "x" + std::to_string(h) +
                " segmentation needs " + std::to_string(n));
  }
  if (tolerance_px < 0 || tolerance_px > 1000) {
    throw Error("evaluateOversegmentation: tolerance_px = " + std::to_string(tolerance_px) +
                " (expected 0..1000)");
  }
  const std::vector<int>& ps = seg.pixel_segment;
  for (std::size_t i = 0; i < n; ++i) {
    if (ps[i] < -1 || ps[i] >= static_cast<int>(seg.segments.size())) {
      throw Error("evaluateOversegmentation: pixel " + std::to_string(i) + " has segment id " +
                  std::to_string(ps[i]) + " but there are " + std::to_string(seg.segments.size()) +
                  " segments");
    }
  }

  OversegmentationQuality quality;
  quality.segment_count = static_cast<int>(seg.segments.size());

  // --- boundary recall ------------------------------------------------------
  // Segment boundary map, then "is there one within the square window" as a
  // separable box test on prefix sums (rows, then columns).
  std::vector<std::uint8_t> seg_boundary(n, 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (x + 1 < w && ps[i] != ps[i + 1]) seg_boundary[i] = seg_boundary[i + 1] = 1;
      if (y + 1 < h && ps[i] != ps[i + w]) seg_boundary[i] = seg_boundary[i + w] = 1;
    }
  }
  std::vector<std::uint8_t> near_rows(n, 0);
  std::vector<int> prefix(static_cast<std::size_t>(std::max(w, h)) + 1);
  for (int y = 0; y < h; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * w;
    prefix[0] = 0;
    for (int x = 0; x < w; ++x) prefix[x + 1] = prefix[x] + seg_boundary[row + x];
    for (int x = 0; x < w; ++x) {
      const int lo = std::max(0, x - tolerance_px);
      const int hi = std::min(w, x + tolerance_px + 1);
      near_rows[row + x] = prefix[hi] > prefix[lo];
    }
  }
  std::vector<std::uint8_t> near_boundary(n, 0);
  for (int x = 0; x < w; ++x) {
    prefix[0] = 0;
    for (int y = 0; y < h; ++y)
      prefix[y + 1] = prefix[y] + near_rows[static_cast<std::size_t>(y) * w + x];
    for (int y = 0; y < h; ++y) {
      const int lo = std::max(0, y - tolerance_px);
      const int hi = std::min(h, y + tolerance_px + 1);
      near_boundary[static_cast<std::size_t>(y) * w + x] = prefix[hi] > prefix[lo];
    }
  }
  std::size_t gt_boundary = 0;
  std::size_t recalled = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const std::uint8_t label = gt_labels[i];
      if (label == kVoidLabel) continue;
      const auto differs = [&](std::size_t j) {
        return gt_labels[j] != kVoidLabel && gt_labels[j] != label;
      };
      const bool is_boundary = (x > 0 && differs(i - 1)) || (x + 1 < w && differs(i + 1)) ||
                               (y > 0 && differs(i - w)) || (y + 1 < h && differs(i + w));
      if (!is_boundary) continue;
      ++gt_boundary;
      recalled += near_boundary[i];
    }
  }
  quality.boundary_recall = gt_boundary > 0
                                ? static_cast<double>(recalled) / static_cast<double>(gt_boundary)
                                : std::numeric_limits<double>::quiet_NaN();

  // --- undersegmentation error ----------------------------------------------
  // GT regions: 4-connected components of equal non-void label (flood fill).
  std::vector<int> region(n, -1);
  std::vector<std::size_t> stack;
  int region_count = 0;
  for (std::size_t start = 0; start < n; ++start) {
    if (gt_labels[start] == kVoidLabel || region[start] >= 0) continue;
    const std::uint8_t label = gt_labels[start];
    region[start] = region_count;
    stack.assign(1, start);
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      const int x = static_cast<int>(i % w);
      const int y = static_cast<int>(i / w);
      const auto visit = [&](std::size_t j) {
        if (region[j] < 0 && gt_labels[j] == label) {
          region[j] = region_count;
          stack.push_back(j);
        }
      };
      if (x > 0) visit(i - 1);
      if (x + 1 < w) visit(i + 1);
      if (y > 0) visit(i - w);
      if (y + 1 < h) visit(i + w);
    }
    ++region_count;
  }
  // Overlaps |s ∩ g| over P (non-void and in a segment), as sorted (s, g) keys.
  std::vector<std::uint64_t> keys;
  keys.reserve(n);
  std::vector<std::size_t> seg_size(seg.segments.size(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (ps[i] < 0 || region[i] < 0) continue;
    ++seg_size[ps[i]];
    keys.push_back((static_cast<std::uint64_t>(ps[i]) << 32) |
                   static_cast<std::uint32_t>(region[i]));
  }
  const std::size_t total = keys.size();
  if (total == 0) {
    quality.undersegmentation_error = std::numeric_limits<double>::quiet_NaN();
    return quality;
  }
  std::sort(keys.begin(), keys.end());
  double leak_sum = 0.0;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    const std::size_t overlap = j - i;
    const std::size_t s_size = seg_size[keys[i] >> 32];
    if (static_cast<double>(overlap) > 0.05 * static_cast<double>(s_size)) {
      leak_sum += static_cast<double>(s_size);
    }
    i = j;
  }
  quality.undersegmentation_error =
      (leak_sum - static_cast<double>(total)) / static_cast<double>(total);
  return quality;
}

}  // namespace findmug
