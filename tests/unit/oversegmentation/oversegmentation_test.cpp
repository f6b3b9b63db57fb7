// Oversegmentation stage: finalisation, quality measures, and both
// oversegmenters (PCL supervoxels and the organized one) on ray-cast
// synthetic scenes with known surfaces and on real NYU frames.
#include "findmug/oversegmentation/oversegmentation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/common/error.hpp"
#include "findmug/features/features.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/labels/labels.hpp"
#include "common/int_runs.hpp"
#include "oversegmentation/lab_internal.hpp"
#include "oversegmentation/oversegmentation_internal.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// ---------------------------------------------------------------------------
// Synthetic scenes: a pinhole camera at the origin (x right, y down, z
// forward) ray-casting planes and an axis-aligned box. Ground truth is the
// surface class of each pixel.

struct Scene {
  OrganizedCloud cloud;
  NormalImage normals;
  std::vector<std::uint8_t> gt;
};

struct Hit {
  float t = std::numeric_limits<float>::infinity();
  Eigen::Vector3f normal;
  Rgb8 color;
  std::uint8_t label = kVoidLabel;
};

// Small deterministic colour noise so that no two pixels tie exactly.
std::uint8_t jitter(std::uint8_t base, int x, int y, int channel) {
  const unsigned hash = (static_cast<unsigned>(x) * 73856093u) ^
                        (static_cast<unsigned>(y) * 19349663u) ^
                        (static_cast<unsigned>(channel) * 83492791u);
  const int v = static_cast<int>(base) + static_cast<int>(hash % 7u) - 3;
  return static_cast<std::uint8_t>(std::clamp(v, 0, 255));
}

struct PlaneSpec {
  int axis;  // 0 x, 1 y, 2 z: the plane is coordinate[axis] = offset
  float offset;
  Rgb8 color;
  std::uint8_t label;
};

struct BoxSpec {
  Eigen::Vector3f lo, hi;
  Rgb8 color;
  std::uint8_t label;
};

Scene castScene(int width, int height, const std::vector<PlaneSpec>& planes,
                const std::vector<BoxSpec>& boxes) {
  const float f = 525.0f * static_cast<float>(width) / 640.0f;
  const float cx = 0.5f * (width - 1), cy = 0.5f * (height - 1);
  Scene s;
  s.cloud.width = s.normals.width = width;
  s.cloud.height = s.normals.height = height;
  const std::size_t n = static_cast<std::size_t>(width) * height;
  s.cloud.points.resize(n);
  s.cloud.colors.resize(n);
  s.normals.normals.resize(n);
  s.gt.assign(n, kVoidLabel);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const Eigen::Vector3f ray((x - cx) / f, (y - cy) / f, 1.0f);
      Hit best;
      for (const PlaneSpec& p : planes) {
        if (std::fabs(ray[p.axis]) < 1e-6f) continue;
        const float t = p.offset / ray[p.axis];
        if (t > 0 && t < best.t) {
          best.t = t;
          best.normal = Eigen::Vector3f::Zero();
          best.normal[p.axis] = p.offset > 0 ? -1.0f : 1.0f;  // towards the camera
          best.color = p.color;
          best.label = p.label;
        }
      }
      for (const BoxSpec& b : boxes) {
        // Slab method; the entry face gives the normal.
        float t_near = 0, t_far = std::numeric_limits<float>::infinity();
        int near_axis = -1;
        bool miss = false;
        for (int a = 0; a < 3 && !miss; ++a) {
          if (std::fabs(ray[a]) < 1e-9f) {
            miss = 0 < b.lo[a] || 0 > b.hi[a];
            continue;
          }
          float t0 = b.lo[a] / ray[a], t1 = b.hi[a] / ray[a];
          if (t0 > t1) std::swap(t0, t1);
          if (t0 > t_near) {
            t_near = t0;
            near_axis = a;
          }
          t_far = std::min(t_far, t1);
          miss = t_near > t_far;
        }
        if (miss || near_axis < 0 || t_near >= best.t) continue;
        best.t = t_near;
        best.normal = Eigen::Vector3f::Zero();
        best.normal[near_axis] = ray[near_axis] > 0 ? -1.0f : 1.0f;
        best.color = b.color;
        best.label = b.label;
      }
      const std::size_t i = static_cast<std::size_t>(y) * width + x;
      if (!std::isfinite(best.t)) {
        s.cloud.points[i] = Eigen::Vector3f(kNaN, kNaN, kNaN);
        s.normals.normals[i] = Eigen::Vector3f(kNaN, kNaN, kNaN);
        continue;
      }
      s.cloud.points[i] = ray * best.t;
      s.cloud.colors[i] = {jitter(best.color.r, x, y, 0), jitter(best.color.g, x, y, 1),
                           jitter(best.color.b, x, y, 2)};
      s.normals.normals[i] = best.normal;
      s.gt[i] = best.label;
    }
  }
  return s;
}

// Floor (y = 1 m below the camera) meeting a wall (z = 3 m) in a crease, in
// the same grey: only geometry separates them.
Scene creaseScene(int width = 320, int height = 240) {
  const Rgb8 grey{128, 128, 128};
  return castScene(width, height, {{1, 1.0f, grey, 1}, {2, 3.0f, grey, 2}}, {});
}

// A red box on a grey floor in front of a beige wall.
Scene boxScene(int width = 320, int height = 240) {
  return castScene(width, height, {{1, 1.0f, {120, 120, 120}, 1}, {2, 4.0f, {200, 190, 150}, 2}},
                   {{{0.2f, 0.5f, 2.0f}, {0.8f, 1.0f, 2.6f}, {200, 30, 30}, 7}});
}

OversegmentationConfig configFor(OversegmenterKind kind, float seed_resolution = 0.1f) {
  OversegmentationConfig c;
  c.kind = kind;
  c.seed_resolution_m = seed_resolution;
  return c;
}

Oversegmentation run(OversegmenterKind kind, const Scene& s, float seed_resolution = 0.1f) {
  return makeOversegmenter(configFor(kind, seed_resolution))->segment(s.cloud, s.normals);
}

// Everything the Oversegmentation contract promises, whatever made it.
void expectWellFormed(const Oversegmentation& seg, const OrganizedCloud& cloud, int min_points,
                      double max_dropped_share) {
  ASSERT_EQ(seg.width, cloud.width);
  ASSERT_EQ(seg.height, cloud.height);
  ASSERT_EQ(seg.pixel_segment.size(), cloud.size());
  const int count = static_cast<int>(seg.segments.size());
  std::size_t valid = 0, dropped = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int id = seg.pixel_segment[i];
    ASSERT_GE(id, -1);
    ASSERT_LT(id, count);
    if (!cloud.valid(i)) {
      ASSERT_EQ(id, -1) << "invalid pixel " << i << " is in a segment";
      continue;
    }
    ++valid;
    dropped += id < 0;
  }
  EXPECT_LE(static_cast<double>(dropped), max_dropped_share * static_cast<double>(valid))
      << dropped << " of " << valid << " valid pixels are in no segment";
  // segments[] is exactly the inverse of pixel_segment.
  std::size_t listed = 0;
  for (int k = 0; k < count; ++k) {
    EXPECT_GE(static_cast<int>(seg.segments[k].size()), std::max(min_points, 1));
    for (const int i : seg.segments[k]) {
      ASSERT_EQ(seg.pixel_segment[i], k);
    }
    listed += seg.segments[k].size();
  }
  EXPECT_EQ(listed, valid - dropped);
  // Edges: in range, first < second, sorted, each once.
  for (std::size_t e = 0; e < seg.edges.size(); ++e) {
    const auto [a, b] = seg.edges[e];
    ASSERT_GE(a, 0);
    ASSERT_LT(a, b);
    ASSERT_LT(b, count);
    if (e > 0) {
      ASSERT_LT(seg.edges[e - 1], seg.edges[e]) << "edges not sorted/unique";
    }
  }
}

// Segments joined by 4-neighbouring pixels, as (a < b) pairs.
std::set<std::pair<int, int>> imageAdjacency(const Oversegmentation& seg) {
  std::set<std::pair<int, int>> out;
  const int w = seg.width;
  for (int y = 0; y < seg.height; ++y) {
    for (int x = 0; x < w; ++x) {
      const int a = seg.pixel_segment[static_cast<std::size_t>(y) * w + x];
      for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (x + dx >= w || y + dy >= seg.height) continue;
        const int b = seg.pixel_segment[static_cast<std::size_t>(y + dy) * w + x + dx];
        if (a >= 0 && b >= 0 && a != b) out.emplace(std::min(a, b), std::max(a, b));
      }
    }
  }
  return out;
}

// Number of 4-connected pieces of segment k.
int pieces(const Oversegmentation& seg, int k) {
  std::vector<std::uint8_t> seen(seg.pixel_segment.size(), 0);
  int count = 0;
  for (const int start : seg.segments[k]) {
    if (seen[start]) continue;
    ++count;
    std::vector<int> stack{start};
    seen[start] = 1;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      const int x = i % seg.width, y = i / seg.width;
      for (const auto& [dx, dy] :
           {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
        const int nx = x + dx, ny = y + dy;
        if (nx < 0 || ny < 0 || nx >= seg.width || ny >= seg.height) continue;
        const int j = ny * seg.width + nx;
        if (!seen[j] && seg.pixel_segment[j] == k) {
          seen[j] = 1;
          stack.push_back(j);
        }
      }
    }
  }
  return count;
}

// A regular grid of square cells over the whole image with about `target`
// cells on valid pixels: the baseline an oversegmenter must beat.
Oversegmentation regularGrid(const OrganizedCloud& cloud, int target) {
  std::size_t valid = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) valid += cloud.valid(i);
  const int step = std::max(
      1,
      static_cast<int>(std::lround(std::sqrt(static_cast<double>(valid) / std::max(target, 1)))));
  const int cols = (cloud.width + step - 1) / step;
  Oversegmentation seg;
  seg.width = cloud.width;
  seg.height = cloud.height;
  seg.pixel_segment.assign(cloud.size(), -1);
  for (int y = 0; y < cloud.height; ++y) {
    for (int x = 0; x < cloud.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * cloud.width + x;
      if (cloud.valid(i)) seg.pixel_segment[i] = (y / step) * cols + x / step;
    }
  }
  finalizeOversegmentation(seg, 1);
  return seg;
}

// ---------------------------------------------------------------------------
// finalizeOversegmentation

// intRunEnd (eight values per step) against a plain loop, from every start
// of arrays of runs of 1..20 values (ids, -1 and -2 among them), whose
// lengths put run ends at every position of a step and at the array's end.
TEST(IntRunEnd, FindsTheEndOfEveryRunAsAPlainLoopDoes) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<int> values;
    const std::size_t size = 1 + rng() % 120;
    while (values.size() < size) {
      const int value = static_cast<int>(rng() % 5) - 2;
      const std::size_t length = 1 + rng() % 20;
      for (std::size_t k = 0; k < length && values.size() < size; ++k) values.push_back(value);
    }
    for (std::size_t begin = 0; begin < size; ++begin) {
      std::size_t expected = begin + 1;
      while (expected < size && values[expected] == values[begin]) ++expected;
      ASSERT_EQ(detail::intRunEnd(values.data(), begin, size), expected)
          << "trial " << trial << ", begin " << begin << " of " << size;
      // A shorter limit stops the run there.
      const std::size_t limit = begin + 1 + (size - begin - 1) / 2;
      ASSERT_EQ(detail::intRunEnd(values.data(), begin, limit), std::min(expected, limit));
    }
  }
}

TEST(FinalizeOversegmentation, DropsSmallSegmentsAndRenumbersInIdOrder) {
  Oversegmentation seg;
  seg.width = 4;
  seg.height = 3;
  seg.pixel_segment = {5, 5, 5, -1,  //
                       5, 9, 9, 2,   //
                       7, 9, 9, 2};
  finalizeOversegmentation(seg, 2);
  // 7 has one pixel and goes; 2 -> 0, 5 -> 1, 9 -> 2.
  EXPECT_EQ(seg.pixel_segment, (std::vector<int>{1, 1, 1, -1, 1, 2, 2, 0, -1, 2, 2, 0}));
  ASSERT_EQ(seg.segments.size(), 3u);
  EXPECT_EQ(seg.segments[0], (std::vector<int>{7, 11}));
  EXPECT_EQ(seg.segments[1], (std::vector<int>{0, 1, 2, 4}));
  EXPECT_EQ(seg.segments[2], (std::vector<int>{5, 6, 9, 10}));
  // 4-neighbour adjacency: 5|9 (1-2) and 9|2 (2-0); the dropped 7 joins nothing.
  EXPECT_EQ(seg.edges, (std::vector<std::pair<int, int>>{{0, 2}, {1, 2}}));
}

TEST(FinalizeOversegmentation, KeepsGivenEdgesRemappedWithoutDroppedOnes) {
  Oversegmentation seg;
  seg.width = 3;
  seg.height = 2;
  seg.pixel_segment = {4, 4, 5, 1, 1, 3};
  // 3-4 do not touch in the image but are kept (PCL's adjacency is 3-D);
  // duplicates, reversed pairs and self loops collapse.
  const std::vector<std::pair<int, int>> given = {{4, 3}, {3, 4}, {1, 4}, {4, 5}, {1, 1}, {5, 3}};
  seg.edges = given;
  finalizeOversegmentation(seg, 1, EdgeSource::Keep);
  // All kept at min 1: 1 -> 0, 3 -> 1, 4 -> 2, 5 -> 3.
  EXPECT_EQ(seg.edges, (std::vector<std::pair<int, int>>{{0, 2}, {1, 2}, {1, 3}, {2, 3}}));
  seg.pixel_segment = {4, 4, 5, 1, 1, 3};
  seg.edges = given;
  finalizeOversegmentation(seg, 2, EdgeSource::Keep);
  // 3 and 5 have one pixel each: only 1-4 survives, as 0-1.
  EXPECT_EQ(seg.segments.size(), 2u);
  EXPECT_EQ(seg.edges, (std::vector<std::pair<int, int>>{{0, 1}}));
}

TEST(FinalizeOversegmentation, RejectsBadInput) {
  Oversegmentation seg;
  seg.width = 2;
  seg.height = 2;
  seg.pixel_segment = {0, 0, 0};
  EXPECT_THROW(finalizeOversegmentation(seg, 1), Error);
  seg.pixel_segment = {0, 0, -3, 0};
  EXPECT_THROW(finalizeOversegmentation(seg, 1), Error);
  seg.pixel_segment = {0, 0, 4, 0};  // ids must stay below the pixel count
  try {
    finalizeOversegmentation(seg, 1);
    FAIL() << "no error for id 4 on a 2x2 grid";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("4"), std::string::npos) << e.what();
  }
  seg.pixel_segment = {0, 0, 1, 1};
  seg.edges = {{0, 7}};
  EXPECT_THROW(finalizeOversegmentation(seg, 1, EdgeSource::Keep), Error);
  EXPECT_THROW(finalizeOversegmentation(seg, -1), Error);
  // Pixel indices are ints: a grid of more pixels is refused by name (before
  // anything is sized from it).
  Oversegmentation huge;
  huge.width = 100000;
  huge.height = 100000;
  try {
    finalizeOversegmentation(huge, 1);
    FAIL() << "no error for a 100000x100000 grid";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("int pixel index"), std::string::npos) << e.what();
  }
}

// The finalisation against a plain reference (count, renumber in id order,
// list pixels, set of 4-neighbour pairs) on random blocky images whose widths
// are not multiples of four, with -1 holes and small segments: the counting
// by runs and the four-pixel boundary skip must give the same result
// everywhere, in the vector part, its row tail and the last row.
TEST(FinalizeOversegmentation, MatchesAPlainReferenceOnRandomImages) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const int w = std::uniform_int_distribution<int>(1, 23)(rng);
    const int h = std::uniform_int_distribution<int>(1, 9)(rng);
    // Ids stay below the pixel count (finalizeOversegmentation's contract).
    const int ids = std::min(w * h, std::uniform_int_distribution<int>(1, 12)(rng));
    const int block = std::uniform_int_distribution<int>(1, 5)(rng);
    const int min_points = std::uniform_int_distribution<int>(0, 4)(rng);
    std::uniform_int_distribution<int> pick(-1, ids - 1);
    std::vector<int> image(static_cast<std::size_t>(w) * h);
    // Blocks of one id (long runs and flat rows, as real images have), with
    // single-pixel noise.
    std::vector<int> block_id(static_cast<std::size_t>((w / block + 1) * (h / block + 1)));
    for (int& b : block_id) b = pick(rng);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        int id = block_id[static_cast<std::size_t>((y / block) * (w / block + 1) + x / block)];
        if (std::uniform_int_distribution<int>(0, 9)(rng) == 0) id = pick(rng);
        image[static_cast<std::size_t>(y) * w + x] = id;
      }
    }
    // Reference.
    std::vector<int> count(static_cast<std::size_t>(ids), 0);
    for (const int id : image) {
      if (id >= 0) ++count[id];
    }
    std::vector<int> remap(static_cast<std::size_t>(ids), -1);
    int next = 0;
    for (int id = 0; id < ids; ++id) {
      if (count[id] >= std::max(min_points, 1)) remap[id] = next++;
    }
    std::vector<int> expected_pixels(image.size());
    std::vector<std::vector<int>> expected_lists(static_cast<std::size_t>(next));
    for (std::size_t i = 0; i < image.size(); ++i) {
      expected_pixels[i] = image[i] >= 0 ? remap[image[i]] : -1;
      if (expected_pixels[i] >= 0) expected_lists[expected_pixels[i]].push_back(static_cast<int>(i));
    }
    std::set<std::pair<int, int>> pairs;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const int a = expected_pixels[static_cast<std::size_t>(y) * w + x];
        for (const auto& [nx, ny] : {std::pair{x + 1, y}, std::pair{x, y + 1}}) {
          if (nx >= w || ny >= h) continue;
          const int b = expected_pixels[static_cast<std::size_t>(ny) * w + nx];
          if (a >= 0 && b >= 0 && a != b) pairs.insert({std::min(a, b), std::max(a, b)});
        }
      }
    }
    Oversegmentation seg;
    seg.width = w;
    seg.height = h;
    seg.pixel_segment = image;
    finalizeOversegmentation(seg, min_points);
    SCOPED_TRACE("trial " + std::to_string(trial) + ", " + std::to_string(w) + "x" +
                 std::to_string(h));
    ASSERT_EQ(seg.pixel_segment, expected_pixels);
    ASSERT_EQ(seg.segments, expected_lists);
    ASSERT_EQ(seg.edges, (std::vector<std::pair<int, int>>(pairs.begin(), pairs.end())));
  }
}

// A recycled Oversegmentation (the daemon reuses one per frame in flight)
// keeps its pixel lists' capacity. Over a long stream of frames with unlike
// segment sizes that capacity must stay near one frame's worth: handed out
// in any order, every list grew to fit the largest segment it ever met, and
// the heap in use of a 30 fps soak climbed 10 MB a minute.
TEST(FinalizeOversegmentation, RecycledPixelListsStayNearOneFrameOfCapacity) {
  constexpr int w = 96, h = 64, n = w * h;
  std::mt19937 rng(7);
  Oversegmentation seg;
  std::size_t worst = 0;
  for (int frame = 0; frame < 3000; ++frame) {
    // Row-major runs: one big segment (20..60 % of the frame) at a random
    // place among 20..60 small ones of random lengths.
    const int segments = std::uniform_int_distribution<int>(20, 60)(rng);
    const int big = std::uniform_int_distribution<int>(n / 5, 3 * n / 5)(rng);
    const int big_at = std::uniform_int_distribution<int>(0, segments - 1)(rng);
    std::vector<int> lengths(static_cast<std::size_t>(segments));
    std::exponential_distribution<double> small(1.0);
    double total = 0.0;
    std::vector<double> weights(lengths.size());
    for (auto& x : weights) total += (x = small(rng));
    for (int k = 0; k < segments; ++k)
      lengths[k] = k == big_at ? big : std::max(1, static_cast<int>((n - big) * weights[k] / total));
    seg.width = w;
    seg.height = h;
    seg.pixel_segment.assign(n, -1);
    int p = 0;
    for (int k = 0; k < segments && p < n; ++k)
      for (int i = 0; i < lengths[k] && p < n; ++i) seg.pixel_segment[p++] = k;
    finalizeOversegmentation(seg, 1);
    std::size_t capacity = 0, pixels = 0;
    for (const auto& list : seg.segments) {
      capacity += list.capacity();
      pixels += list.size();
    }
    ASSERT_EQ(pixels, static_cast<std::size_t>(std::min(p, n)));
    worst = std::max(worst, capacity);
  }
  // Measured: 2.3 frames of capacity by rank; 41 when lists were handed out
  // in any order (and still growing).
  EXPECT_LE(worst, 4u * n) << "pixel-list capacity of a recycled segmentation, in pixels";
}

// ---------------------------------------------------------------------------
// evaluateOversegmentation on hand-made 4x4 images.

Oversegmentation fromIds(int w, int h, std::vector<int> ids) {
  Oversegmentation seg;
  seg.width = w;
  seg.height = h;
  seg.pixel_segment = std::move(ids);
  finalizeOversegmentation(seg, 1);
  return seg;
}

const std::vector<std::uint8_t> kLeftRight = {1, 1, 2, 2,  //
                                              1, 1, 2, 2,  //
                                              1, 1, 2, 2,  //
                                              1, 1, 2, 2};

TEST(EvaluateOversegmentation, PerfectSegmentationScoresOne) {
  const auto q = evaluateOversegmentation(
      fromIds(4, 4, {0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1}), kLeftRight, 0);
  EXPECT_DOUBLE_EQ(q.boundary_recall, 1.0);
  EXPECT_DOUBLE_EQ(q.undersegmentation_error, 0.0);
  EXPECT_EQ(q.segment_count, 2);
}

TEST(EvaluateOversegmentation, OneSegmentLeaksOverEverything) {
  const auto q = evaluateOversegmentation(fromIds(4, 4, std::vector<int>(16, 0)), kLeftRight, 2);
  EXPECT_DOUBLE_EQ(q.boundary_recall, 0.0);
  // The 16-pixel segment is counted for both halves: (32 - 16) / 16.
  EXPECT_DOUBLE_EQ(q.undersegmentation_error, 1.0);
  EXPECT_EQ(q.segment_count, 1);
}

TEST(EvaluateOversegmentation, ToleranceDecidesWhichBoundaryPixelsAreRecalled) {
  // Horizontal split against a vertical GT boundary (columns 1 and 2): only
  // the crossings (rows 1-2) are recalled at tolerance 0, all at tolerance 1.
  const auto seg = fromIds(4, 4, {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1});
  EXPECT_DOUBLE_EQ(evaluateOversegmentation(seg, kLeftRight, 0).boundary_recall, 0.5);
  EXPECT_DOUBLE_EQ(evaluateOversegmentation(seg, kLeftRight, 1).boundary_recall, 1.0);
  EXPECT_DOUBLE_EQ(evaluateOversegmentation(seg, kLeftRight, 1).undersegmentation_error, 1.0);
}

TEST(EvaluateOversegmentation, VoidIsIgnoredAndPixelsOutsideSegmentsDoNotCount) {
  // Column 0 void; its boundary with label 1 is not a GT boundary. Column 3
  // is in no segment; it still makes GT boundary pixels in column 2 (labels
  // 1|2), recalled because -1 differs from the segment next to it.
  const std::vector<std::uint8_t> gt = {255, 1, 1, 2,  //
                                        255, 1, 1, 2,  //
                                        255, 1, 1, 2,  //
                                        255, 1, 1, 2};
  const auto seg = fromIds(4, 4, {0, 0, 0, -1, 0, 0, 0, -1, 0, 0, 0, -1, 0, 0, 0, -1});
  const auto q = evaluateOversegmentation(seg, gt, 0);
  EXPECT_DOUBLE_EQ(q.boundary_recall, 1.0);  // 8 GT boundary pixels (columns 2, 3), all hit
  // P = columns 1-2 (8 pixels), all label 1 in one region: no leakage.
  EXPECT_DOUBLE_EQ(q.undersegmentation_error, 0.0);
}

TEST(EvaluateOversegmentation, SmallOverlapsBelowFivePercentAreForgiven) {
  // 10x4: GT label 1 everywhere but two pixels of label 2 in the right half.
  std::vector<std::uint8_t> gt(40, 1);
  gt[9] = gt[19] = 2;
  std::vector<int> two_halves(40);
  for (int i = 0; i < 40; ++i) two_halves[i] = (i % 10) < 5 ? 0 : 1;
  // Right segment: 20 pixels, 2 in region 2 > 5 % of 20 -> counted twice:
  // (20 + 20 + 20 - 40) / 40.
  EXPECT_DOUBLE_EQ(
      evaluateOversegmentation(fromIds(10, 4, two_halves), gt, 0).undersegmentation_error, 0.5);
  // One 40-pixel segment: 2 <= 5 % of 40 -> region 2 is forgiven.
  EXPECT_DOUBLE_EQ(evaluateOversegmentation(fromIds(10, 4, std::vector<int>(40, 0)), gt, 0)
                       .undersegmentation_error,
                   0.0);
}

TEST(EvaluateOversegmentation, GroundTruthRegionsAreConnectedComponents) {
  // Labels 1 2 1 in a row: the two 1-pieces are different regions, so the
  // single segment is counted three times: (15 - 5) / 5.
  const std::vector<std::uint8_t> gt = {1, 1, 2, 1, 1};
  const auto q = evaluateOversegmentation(fromIds(5, 1, {0, 0, 0, 0, 0}), gt, 0);
  EXPECT_DOUBLE_EQ(q.undersegmentation_error, 2.0);
}

TEST(EvaluateOversegmentation, UndefinedCasesAreNaNAndBadInputThrows) {
  const auto q = evaluateOversegmentation(fromIds(2, 2, {0, 0, 0, 0}),
                                          std::vector<std::uint8_t>(4, kVoidLabel), 1);
  EXPECT_TRUE(std::isnan(q.boundary_recall));
  EXPECT_TRUE(std::isnan(q.undersegmentation_error));
  EXPECT_THROW(evaluateOversegmentation(fromIds(2, 2, {0, 0, 0, 0}), {1, 1, 1}, 1), Error);
  EXPECT_THROW(evaluateOversegmentation(fromIds(2, 2, {0, 0, 0, 0}), {1, 1, 1, 1}, -1), Error);
}

// ---------------------------------------------------------------------------
// Config and input checks

TEST(OversegmentationConfig, BadValuesNameTheField) {
  const auto expectFieldError = [](OversegmentationConfig c, const std::string& field) {
    try {
      makeOversegmenter(c);
      ADD_FAILURE() << "no error for bad " << field;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  OversegmentationConfig c;
  c.seed_resolution_m = 0.005f;  // below the voxel resolution
  expectFieldError(c, "seed_resolution_m");
  c = {};
  c.voxel_resolution_m = kNaN;
  expectFieldError(c, "voxel_resolution_m");
  c = {};
  c.color_importance = -1.0f;
  expectFieldError(c, "color_importance");
  c = {};
  c.max_iterations = 0;
  expectFieldError(c, "max_iterations");
  c = {};
  c.search_window_factor = 0;
  expectFieldError(c, "search_window_factor");
  c = {};
  c.organized_seed_density = 0.0f;
  expectFieldError(c, "organized_seed_density");
  c = {};
  c.min_segment_points = -5;
  expectFieldError(c, "min_segment_points");
}

class BothOversegmenters : public ::testing::TestWithParam<OversegmenterKind> {};

std::string kindName(const ::testing::TestParamInfo<OversegmenterKind>& info) {
  return info.param == OversegmenterKind::Organized ? "Organized" : "Pcl";
}

TEST_P(BothOversegmenters, RejectsMismatchedNormals) {
  Scene s = creaseScene(64, 48);
  s.normals.normals.pop_back();
  EXPECT_THROW(makeOversegmenter(configFor(GetParam()))->segment(s.cloud, s.normals), Error);
  s = creaseScene(64, 48);
  s.cloud.colors.resize(10);
  EXPECT_THROW(makeOversegmenter(configFor(GetParam()))->segment(s.cloud, s.normals), Error);
}

TEST_P(BothOversegmenters, EmptyCloudGivesNoSegments) {
  Scene s = creaseScene(64, 48);
  for (auto& p : s.cloud.points) p = Eigen::Vector3f(kNaN, kNaN, kNaN);
  const Oversegmentation seg =
      makeOversegmenter(configFor(GetParam()))->segment(s.cloud, s.normals);
  EXPECT_TRUE(seg.segments.empty());
  EXPECT_TRUE(seg.edges.empty());
  EXPECT_EQ(std::count(seg.pixel_segment.begin(), seg.pixel_segment.end(), -1),
            static_cast<long>(s.cloud.size()));
}

TEST_P(BothOversegmenters, CreaseIsASegmentBoundary) {
  const Scene s = creaseScene();
  const Oversegmentation seg = run(GetParam(), s);
  expectWellFormed(seg, s.cloud, 20, GetParam() == OversegmenterKind::Organized ? 0.0 : 0.05);
  const auto q = evaluateOversegmentation(seg, s.gt, 2);
  // Floor and wall have the same colour: only the normal/3-D terms find it.
  EXPECT_GT(q.boundary_recall, 0.9);
  EXPECT_LT(q.undersegmentation_error, 0.1);
  EXPECT_GT(q.segment_count, 20);
}

TEST_P(BothOversegmenters, BoxEdgesAreSegmentBoundaries) {
  const Scene s = boxScene();
  const Oversegmentation seg = run(GetParam(), s);
  // PCL leaves voxels that no supervoxel reached unlabelled (3 % here).
  expectWellFormed(seg, s.cloud, 20, GetParam() == OversegmenterKind::Organized ? 0.0 : 0.05);
  const auto q = evaluateOversegmentation(seg, s.gt, 2);
  EXPECT_GT(q.boundary_recall, 0.85);
  EXPECT_LT(q.undersegmentation_error, 0.15);
  // The box gets segments of its own: some segment lies mostly on it.
  int box_segments = 0;
  for (const auto& pixels : seg.segments) {
    const auto on_box =
        std::count_if(pixels.begin(), pixels.end(), [&](int i) { return s.gt[i] == 7; });
    box_segments += on_box * 10 > static_cast<long>(pixels.size()) * 9;
  }
  EXPECT_GE(box_segments, 2);
}

TEST_P(BothOversegmenters, SegmentCountScalesWithInverseSquareSeedResolution) {
  const Scene s = creaseScene();
  const double fine = static_cast<double>(run(GetParam(), s, 0.1f).segments.size());
  const double coarse = static_cast<double>(run(GetParam(), s, 0.2f).segments.size());
  ASSERT_GT(coarse, 0);
  EXPECT_GT(fine / coarse, 2.5) << fine << " vs " << coarse;
  EXPECT_LT(fine / coarse, 6.0) << fine << " vs " << coarse;
}

TEST_P(BothOversegmenters, AdjacentSegmentsAreConnectedByEdges) {
  const Scene s = boxScene();
  const Oversegmentation seg = run(GetParam(), s);
  ASSERT_FALSE(seg.edges.empty());
  std::vector<int> degree(seg.segments.size(), 0);
  for (const auto& [a, b] : seg.edges) {
    ++degree[a];
    ++degree[b];
  }
  const auto isolated = std::count(degree.begin(), degree.end(), 0);
  const auto touching = imageAdjacency(seg);
  if (GetParam() == OversegmenterKind::Organized) {
    // Image-grid adjacency, exactly; every segment has a neighbour in this
    // continuous scene.
    const std::set<std::pair<int, int>> edges(seg.edges.begin(), seg.edges.end());
    EXPECT_EQ(edges, touching);
    EXPECT_EQ(isolated, 0);
  } else {
    // PCL's voxel adjacency (3-D, so it also links segments that do not
    // touch in the image): most segments touching in the image are
    // neighbours in it too, and few segments are left without any.
    std::size_t found = 0;
    for (const auto& e : touching) {
      found += std::binary_search(seg.edges.begin(), seg.edges.end(), e);
    }
    EXPECT_GT(static_cast<double>(found), 0.8 * static_cast<double>(touching.size()))
        << found << " of " << touching.size() << " image neighbours are PCL edges";
    EXPECT_LT(static_cast<double>(isolated), 0.02 * static_cast<double>(seg.segments.size()))
        << isolated << " of " << seg.segments.size() << " segments have no PCL neighbour";
  }
}

INSTANTIATE_TEST_SUITE_P(Kinds, BothOversegmenters,
                         ::testing::Values(OversegmenterKind::Organized,
                                           OversegmenterKind::PclSupervoxels),
                         kindName);

// ---------------------------------------------------------------------------
// Organized oversegmenter specifics

TEST(OrganizedOversegmenter, SegmentsAreConnectedAndAvoidHoles) {
  Scene s = boxScene();
  // A hole of missing depth, as a Kinect gives on black or shiny surfaces.
  for (int y = 60; y < 100; ++y) {
    for (int x = 40; x < 110; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * s.cloud.width + x;
      s.cloud.points[i] = Eigen::Vector3f(kNaN, kNaN, kNaN);
      s.normals.normals[i] = Eigen::Vector3f(kNaN, kNaN, kNaN);
      s.gt[i] = kVoidLabel;
    }
  }
  const Oversegmentation seg = run(OversegmenterKind::Organized, s);
  expectWellFormed(seg, s.cloud, 20, 0.02);
  for (int k = 0; k < static_cast<int>(seg.segments.size()); ++k) {
    EXPECT_EQ(pieces(seg, k), 1) << "segment " << k << " is in pieces";
  }
}

// The organized oversegmenter decides most full-resolution pixels eight at
// a time with AVX2 (refineBlockAvx2) and the rest one by one, sums its
// cluster centres four pixels at a time (addRunChannelsAvx2), works out
// the seed density eight coarse pixels at a time (seedDensity8) and runs its
// window search eight pixels at a time (assignWindowAvx, against SSE2's
// four): the same segmentation as the scalar and SSE2 code for all four, on
// the NYU frames and on the box scene with holes, NaN coordinates, a zero
// depth and image widths that leave a tail of every length after the blocks;
// and with normals of length 1 to 5, for which the normal term of the
// distance goes negative (a shortcut that assumed unit normals, as one tried
// in perf-log §9w, fails there).
TEST(OrganizedOversegmenter, AvxRefinementMatchesTheScalarCodeExactly) {
  FINDMUG_REQUIRE_DATA(root, "nyuv2_labeled");
  OversegmentationConfig config;
  config.kind = OversegmenterKind::Organized;
  const auto simd = detail::makeOrganizedOversegmenter(config, detail::OversegSimd::Auto);
  const auto scalar = detail::makeOrganizedOversegmenter(config, detail::OversegSimd::Off);
  const auto expectSame = [&](const OrganizedCloud& cloud, const NormalImage& normals,
                              const std::string& what) {
    const Oversegmentation a = simd->segment(cloud, normals);
    const Oversegmentation b = scalar->segment(cloud, normals);
    EXPECT_EQ(a.pixel_segment, b.pixel_segment) << what;
    EXPECT_EQ(a.segments.size(), b.segments.size()) << what;
  };
  const DatasetFolder dataset(root.string());
  ASSERT_GE(dataset.size(), 30u);
  for (std::size_t index = 0; index < dataset.size(); ++index) {
    const OrganizedCloud cloud = frameToCloud(dataset.load(index).frame);
    expectSame(cloud, computeNormals(cloud, NormalConfig{}), "NYU frame " + std::to_string(index));
  }
  const Scene full = boxScene();
  for (const int width : {full.cloud.width, 161, 150, 31, 17, 9}) {
    Scene s = full;
    // Crop to `width` columns, then spoil some points.
    OrganizedCloud cloud;
    NormalImage normals;
    cloud.width = normals.width = width;
    cloud.height = normals.height = s.cloud.height;
    for (int y = 0; y < s.cloud.height; ++y) {
      for (int x = 0; x < width; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * s.cloud.width + x;
        Eigen::Vector3f p = s.cloud.points[i];
        const int k = y * width + x;
        if (k % 37 == 5) p.x() = kNaN;
        if (k % 41 == 7) p.y() = std::numeric_limits<float>::infinity();
        if (k % 43 == 9) p.z() = 0.0f;
        if (y > 40 && y < 60 && x > 20 && x < 50) p = Eigen::Vector3f::Constant(kNaN);
        cloud.points.push_back(p);
        cloud.colors.push_back(s.cloud.colors[i]);
        normals.normals.push_back(s.normals.normals[i]);
      }
    }
    expectSame(cloud, normals, "box scene " + std::to_string(width) + " px wide");
  }
  for (std::size_t index = 0; index < 4; ++index) {
    const OrganizedCloud cloud = frameToCloud(dataset.load(index).frame);
    NormalImage normals = computeNormals(cloud, NormalConfig{});
    for (std::size_t i = 0; i < normals.normals.size(); ++i) {
      normals.normals[i] *= 1.0f + static_cast<float>(i % 5);  // lengths 1 .. 5
    }
    expectSame(cloud, normals, "NYU frame " + std::to_string(index) + ", long normals");
  }
}

TEST(OrganizedOversegmenter, ColourAloneSeparatesCoplanarRegions) {
  // One wall, left half blue and right half yellow: no geometric cue.
  Scene s = castScene(320, 240, {{2, 2.5f, {230, 220, 40}, 2}}, {});
  for (int y = 0; y < s.cloud.height; ++y) {
    for (int x = 0; x < s.cloud.width / 2 + 7; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * s.cloud.width + x;
      s.cloud.colors[i] = {jitter(30, x, y, 0), jitter(60, x, y, 1), jitter(200, x, y, 2)};
      s.gt[i] = 7;
    }
  }
  const Oversegmentation seg = run(OversegmenterKind::Organized, s);
  expectWellFormed(seg, s.cloud, 20, 0.0);
  const auto q = evaluateOversegmentation(seg, s.gt, 2);
  EXPECT_GT(q.boundary_recall, 0.9);
  EXPECT_LT(q.undersegmentation_error, 0.1);
}

TEST(OrganizedOversegmenter, SeedDensityTunesTheSegmentCount) {
  const Scene s = creaseScene();
  OversegmentationConfig c = configFor(OversegmenterKind::Organized, 0.2f);
  const double base =
      static_cast<double>(makeOversegmenter(c)->segment(s.cloud, s.normals).segments.size());
  c.organized_seed_density *= 2.0f;
  const double denser =
      static_cast<double>(makeOversegmenter(c)->segment(s.cloud, s.normals).segments.size());
  EXPECT_GT(denser / base, 1.8) << denser << " vs " << base;
  EXPECT_LT(denser / base, 2.2) << denser << " vs " << base;
}

TEST(OrganizedOversegmenter, FarSurfacesGetSmallerImagePatches) {
  // Seeds are spaced in metres, not pixels: a wall at 4 m has image patches
  // about (4/1)^2 = 16 times smaller than one at 1 m.
  const Scene near_wall = castScene(320, 240, {{2, 1.0f, {128, 128, 128}, 2}}, {});
  const Scene far_wall = castScene(320, 240, {{2, 4.0f, {128, 128, 128}, 2}}, {});
  const double near_count =
      static_cast<double>(run(OversegmenterKind::Organized, near_wall).segments.size());
  const double far_count =
      static_cast<double>(run(OversegmenterKind::Organized, far_wall).segments.size());
  ASSERT_GT(near_count, 0);
  EXPECT_GT(far_count / near_count, 8.0) << far_count << " vs " << near_count;
  EXPECT_LT(far_count / near_count, 32.0) << far_count << " vs " << near_count;
}

// ---------------------------------------------------------------------------
// Real data: NYU Depth V2 labelled frames.

TEST(OversegmentationNyu, BothBeatARegularGridAndAgreeOnTheCount) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  const DatasetFolder dataset(dir.string());
  ASSERT_GE(dataset.size(), 2u);
  const auto organized = makeOversegmenter(configFor(OversegmenterKind::Organized));
  const auto pcl = makeOversegmenter(configFor(OversegmenterKind::PclSupervoxels));
  // The last frame (0433) has raw Kinect depth with holes (a third of the
  // pixels): well-formed output there, but few GT boundaries to score.
  for (const std::size_t index : {std::size_t{0}, dataset.size() / 2, dataset.size() - 1}) {
    const LabeledFrame lf = dataset.load(index);
    SCOPED_TRACE(lf.name);
    const OrganizedCloud cloud = frameToCloud(lf.frame);
    const NormalImage normals = computeNormals(cloud, NormalConfig{});
    const Oversegmentation a = organized->segment(cloud, normals);
    const Oversegmentation b = pcl->segment(cloud, normals);
    expectWellFormed(a, cloud, 20, 0.05);
    expectWellFormed(b, cloud, 20, 0.25);
    for (int k = 0; k < static_cast<int>(a.segments.size()); ++k) {
      ASSERT_EQ(pieces(a, k), 1) << "organized segment " << k << " is in pieces";
    }
    if (index == dataset.size() - 1) continue;
    // A regular grid of as many cells already recalls most GT boundaries
    // within 2 px (its straight lines cover much of the image), so compare
    // at 1 px, and on leakage.
    const auto qa = evaluateOversegmentation(a, lf.labels, 1);
    const auto qb = evaluateOversegmentation(b, lf.labels, 1);
    const auto qga = evaluateOversegmentation(regularGrid(cloud, qa.segment_count), lf.labels, 1);
    const auto qgb = evaluateOversegmentation(regularGrid(cloud, qb.segment_count), lf.labels, 1);
    EXPECT_GT(qa.segment_count, 150);
    EXPECT_LT(qa.segment_count, 5000);
    EXPECT_GT(qb.segment_count, 150);
    EXPECT_LT(qb.segment_count, 5000);
    // Same seed resolution, comparable patch count (the default density is
    // calibrated on these frames).
    EXPECT_LT(std::abs(qa.segment_count - qb.segment_count), 0.3 * qb.segment_count)
        << qa.segment_count << " organized vs " << qb.segment_count << " PCL";
    EXPECT_GT(qa.boundary_recall, qga.boundary_recall + 0.03)
        << "organized " << qa.boundary_recall << " vs grid " << qga.boundary_recall;
    EXPECT_LT(qa.undersegmentation_error, 0.9 * qga.undersegmentation_error)
        << "organized " << qa.undersegmentation_error << " vs grid " << qga.undersegmentation_error;
    EXPECT_GT(qb.boundary_recall, qgb.boundary_recall + 0.03)
        << "PCL " << qb.boundary_recall << " vs grid " << qgb.boundary_recall;
    EXPECT_LT(qb.undersegmentation_error, qgb.undersegmentation_error)
        << "PCL " << qb.undersegmentation_error << " vs grid " << qgb.undersegmentation_error;
  }
}

// The organized oversegmenter's colour conversion: the AVX2 path (eight
// colours at a time, tables read by gathers) must give the scalar code's
// bits for every one of the 2^24 colours, read through a scrambled pixel
// index as the oversegmenter reads them, and with counts that leave a tail
// for the scalar code. (Where the CPU has no AVX2 both runs are scalar.)
TEST(OrganizedLab, AvxMatchesTheScalarCodeBitForBitOnEveryColour) {
  constexpr int kBlock = 1 << 16;
  std::vector<Rgb8> colors(kBlock);
  std::vector<int> pixel(kBlock);
  std::mt19937 rng(5);
  std::vector<float> simd(3 * kBlock), scalar(3 * kBlock);
  float max_error = 0.0f;
  for (int red = 0; red < 256; ++red) {
    for (int i = 0; i < kBlock; ++i) {
      colors[i] = {static_cast<std::uint8_t>(red), static_cast<std::uint8_t>(i >> 8),
                   static_cast<std::uint8_t>(i & 255)};
      pixel[i] = i;
    }
    std::shuffle(pixel.begin(), pixel.end(), rng);
    const std::size_t count = kBlock - static_cast<std::size_t>(red % 8);  // tails of 0..7
    float* s = simd.data();
    float* c = scalar.data();
    detail::labFromRgb(colors.data(), pixel.data(), count, s, s + kBlock, s + 2 * kBlock,
                       detail::LabSimd::Auto);
    detail::labFromRgb(colors.data(), pixel.data(), count, c, c + kBlock, c + 2 * kBlock,
                       detail::LabSimd::Off);
    for (int channel = 0; channel < 3; ++channel) {
      ASSERT_EQ(std::memcmp(s + channel * kBlock, c + channel * kBlock, count * sizeof(float)), 0)
          << "red " << red << ", channel " << channel;
    }
    // And the tables stay within 0.01 of the exact conversion.
    for (std::size_t j = 0; j < count; j += 97) {
      const Eigen::Vector3f exact = rgbToLab(colors[pixel[j]]);
      max_error = std::max({max_error, std::fabs(s[j] - exact.x()),
                            std::fabs(s[kBlock + j] - exact.y()),
                            std::fabs(s[2 * kBlock + j] - exact.z())});
    }
  }
  EXPECT_LT(max_error, 0.01f);
}

}  // namespace
}  // namespace findmug
