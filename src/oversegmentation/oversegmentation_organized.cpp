// The fast oversegmenter (issue 7): VCCS-like supervoxels computed on the
// image grid instead of an octree.
//
// Why it is fast: the organized cloud already knows each point's neighbours,
// so there is no voxelisation, no octree and no k-d tree. Clustering is SLIC
// (Achanta et al. 2012) with PCL's VCCS distance and importances:
//
//   D = color_importance   * |Lab_p - Lab_c| / 80
//     + spatial_importance * |xyz_p - xyz_c| / seed_resolution
//     + normal_importance  * (1 - |n_p . n_c|)
//
// (PCL uses |RGB| / 255; kLabScale below puts CIELAB on the same scale.)
//
// Steps:
//  1. A half-resolution feature grid (one usable pixel of each 2x2 block:
//     CIELAB through lookup tables, xyz, normal; structure of arrays). Seeds
//     and iterations run on it, which quarters their cost.
//  2. Seeds: each pixel covers (z/fx)(z/fy)/cos(theta) m^2 of surface (theta:
//     normal vs viewing ray, capped; footprint capped beyond 4 m as PCL's
//     seeding fades out there). The image is cut k-d-tree style, longer side
//     first, into cells holding about one seed's worth of surface,
//     seed_resolution^2 / organized_seed_density, so seeds are about
//     seed_resolution apart on the surface at every depth and slant, as
//     PCL's 3-D seeding gives, and the count scales with
//     organized_seed_density / seed_resolution^2. The focal lengths come from
//     the cloud itself (u = fx x/z + cx is linear). Each cell's seed goes to
//     the usable pixel nearest its centre, then to the lowest-gradient pixel
//     of its 3x3 neighbourhood (SLIC), off colour and depth edges.
//  3. max_iterations rounds of: every cluster scans a window of
//     search_window_factor times its cell around its centre (SSE2) and claims
//     the pixels it is nearest to; centres become the means.
//  4. Full resolution: a pixel takes the label its nearest coarse samples
//     agree on, or along boundaries the nearest of their clusters.
//  5. Connectivity (on horizontal runs): each 4-connected piece of a label
//     becomes its own segment; pieces smaller than max(min_segment_points, a
//     quarter of the cell) merge into the neighbouring piece they share the
//     longest border with.
//  6. finalizeOversegmentation: drop what is still too small (islands in
//     invalid depth), renumber, 4-neighbour adjacency.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/cpu_features.hpp"
#include "findmug/common/error.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "common/int_runs.hpp"
#include "oversegmentation/lab_internal.hpp"
#include "oversegmentation/oversegmentation_internal.hpp"
#include "common/scratch.hpp"
#include "common/simd_table.hpp"
#include "common/simd_vec3.hpp"

namespace findmug {
namespace {

// CIELAB distance to PCL's colour scale (|dRGB| / 255): on the 31 NYU frames
// the mean |dLab| between pixels 9 px apart is 79.5 times their mean
// |dRGB| / 255, so |dLab| / 80 makes color_importance mean what it means to PCL.
constexpr float kLabScale = 1.0f / 80.0f;
constexpr float kMinCosine = 0.25f;  // slant cap: one pixel counts as at most 4 facing ones
// Beyond about 4 m patches stop shrinking in the image: a pixel's footprint
// z^2 / cos (in units of (1/f)^2 m^2, see placeSeeds) is capped at (4 m)^2.
// This mirrors PCL: it keeps a seed only when more than
// 0.05 * pi * (seed/2)^2 / voxel^2 voxels lie within seed/2 of it, and its
// single-camera voxels are voxel * z wide, so seeds thin out from about 4 m
// and stop at z^2 = 1 / (0.05 * pi / 4), about 5 m, whatever the
// resolutions; far surfaces get few, large supervoxels. The cap (fitted with
// organized_seed_density on the NYU frames) also keeps far patches big
// enough for stable features.
constexpr double kMaxFootprint = 4.0 * 4.0;
constexpr int kCoarseStride = 2;
constexpr int kUnassigned = -2;  // usable pixel that no cluster reached


// sRGB (D65) -> CIELAB with tables: a 256-entry sRGB -> linear table and a
// table of the CIELAB f(t) (cube root above the knee) with linear
// interpolation, |error| < 0.01 in L*, a*, b*. std::cbrt per pixel would
// cost more than the whole clustering.
class LabConverter {
 public:
  LabConverter() {
    for (int v = 0; v < 256; ++v) {
      const double c = v / 255.0;
      linear_[v] =
          static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    for (int i = 0; i <= kFSize; ++i) {
      const double t = static_cast<double>(i) * kFMax / kFSize;
      constexpr double kDelta = 6.0 / 29.0;
      f_[i] = static_cast<float>(
          t > kDelta * kDelta * kDelta ? std::cbrt(t) : t / (3 * kDelta * kDelta) + 4.0 / 29.0);
    }
    f_[kFSize + 1] = f_[kFSize];
    detail::fillInterpolationSteps(f_.data(), kFSize + 1, f_step_.data());
  }

  // convert() of colors[pixel[j]] into l[j], a[j], b[j] for j < count.
  void convertBatch(const Rgb8* colors, const int* pixel, std::size_t count, float* l, float* a,
                    float* b, detail::LabSimd simd) const {
    std::size_t j = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
    if (simd == detail::LabSimd::Auto && detail::cpuHasAvx2()) {
      j = convertBatchAvx2(colors, pixel, count, l, a, b);
    }
#else
    (void)simd;
#endif
    for (; j < count; ++j) convert(colors[pixel[j]], l[j], a[j], b[j]);
  }

  void convert(const Rgb8& rgb, float& l, float& a, float& b) const {
    const float r = linear_[rgb.r];
    const float g = linear_[rgb.g];
    const float bl = linear_[rgb.b];
    // Linear sRGB -> XYZ, each row divided by the D65 white point.
    const float x = (0.4124564f * r + 0.3575761f * g + 0.1804375f * bl) * (1.0f / 0.95047f);
    const float y = 0.2126729f * r + 0.7151522f * g + 0.0721750f * bl;
    const float z = (0.0193339f * r + 0.1191920f * g + 0.9503041f * bl) * (1.0f / 1.08883f);
    const float fx = f(x);
    const float fy = f(y);
    const float fz = f(z);
    l = 116.0f * fy - 16.0f;
    a = 500.0f * (fx - fy);
    b = 200.0f * (fy - fz);
  }

 private:
  static constexpr int kFSize = 4096;
  static constexpr float kFMax = 1.0f;  // t = X/Xn etc. never exceeds 1 (+ rounding) for sRGB

  float f(float t) const {
    const float pos = std::clamp(t, 0.0f, kFMax) * (kFSize / kFMax);
    const int i = static_cast<int>(pos);
    const float frac = pos - static_cast<float>(i);
    return f_[i] + frac * (f_[i + 1] - f_[i]);
  }

#if defined(FINDMUG_AVX2_DISPATCH)
  // convert() eight colours at a time, with the same IEEE operations in the
  // same order (no FMA), so the same bits; the tables are read by gathers.
  // Returns how many it converted (a multiple of 8); the caller does the rest.
  __attribute__((target("avx2"))) std::size_t convertBatchAvx2(const Rgb8* colors,
                                                               const int* pixel, std::size_t count,
                                                               float* l, float* a,
                                                               float* b) const {
    const __m256 one = _mm256_set1_ps(1.0f);
    std::size_t j = 0;
    for (; j + 8 <= count; j += 8) {
      alignas(32) int red[8], green[8], blue[8];
      for (int k = 0; k < 8; ++k) {
        const Rgb8& c = colors[pixel[j + k]];
        red[k] = c.r;
        green[k] = c.g;
        blue[k] = c.b;
      }
      const __m256 r = linearAvx2(red), g = linearAvx2(green), bl = linearAvx2(blue);
      const __m256 x = _mm256_mul_ps(rowAvx2(r, g, bl, 0.4124564f, 0.3575761f, 0.1804375f),
                                     _mm256_set1_ps(1.0f / 0.95047f));
      const __m256 y = rowAvx2(r, g, bl, 0.2126729f, 0.7151522f, 0.0721750f);
      const __m256 z = _mm256_mul_ps(rowAvx2(r, g, bl, 0.0193339f, 0.1191920f, 0.9503041f),
                                     _mm256_set1_ps(1.0f / 1.08883f));
      const __m256 fx = fAvx2(x, one), fy = fAvx2(y, one), fz = fAvx2(z, one);
      _mm256_storeu_ps(l + j, _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(116.0f), fy),
                                            _mm256_set1_ps(16.0f)));
      _mm256_storeu_ps(a + j, _mm256_mul_ps(_mm256_set1_ps(500.0f), _mm256_sub_ps(fx, fy)));
      _mm256_storeu_ps(b + j, _mm256_mul_ps(_mm256_set1_ps(200.0f), _mm256_sub_ps(fy, fz)));
    }
    return j;
  }

  // Helpers are member functions, not lambdas: a lambda in an avx2 function
  // is compiled for the base target.
  __attribute__((target("avx2"))) __m256 linearAvx2(const int* v) const {
    return _mm256_i32gather_ps(linear_.data(),
                               _mm256_load_si256(reinterpret_cast<const __m256i*>(v)), 4);
  }
  // cr * r + cg * g + cb * bl, in convert()'s order.
  __attribute__((target("avx2"))) static __m256 rowAvx2(__m256 r, __m256 g, __m256 bl, float cr,
                                                        float cg, float cb) {
    return _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(cr), r), _mm256_mul_ps(_mm256_set1_ps(cg), g)),
        _mm256_mul_ps(_mm256_set1_ps(cb), bl));
  }

  // f() on eight lanes. max/min stand for std::clamp: they differ only for
  // t = -0 (clamp keeps -0, max gives +0), and both give f_[0] then.
  __attribute__((target("avx2"))) __m256 fAvx2(__m256 t, __m256 one) const {
    static_assert(kFMax == 1.0f, "the clamp below is to [0, 1]");
    const __m256 pos = _mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(t, _mm256_setzero_ps()), one),
                                     _mm256_set1_ps(kFSize / kFMax));
    const __m256i i = _mm256_cvttps_epi32(pos);
    const __m256 frac = _mm256_sub_ps(pos, _mm256_cvtepi32_ps(i));
    return detail::interpolate8(f_step_.data(), i, frac);
  }
#endif

  std::array<float, 256> linear_{};
  std::array<float, kFSize + 2> f_{};
  // (f_[i], f_[i + 1] - f_[i]) for i <= kFSize, for fAvx2 (simd_table.hpp).
  alignas(8) std::array<float, 2 * (kFSize + 1)> f_step_{};
};

const LabConverter& labConverter() {
  static const LabConverter converter;
  return converter;
}

// The L, a and b planes of one row's picked pixels, in `lab` (sized here to
// three planes of picks.size(), the row's capacity).
struct LabPlanes {
  const float* l;
  const float* a;
  const float* b;
};
LabPlanes convertPicks(const OrganizedCloud& cloud, const std::vector<int>& picks,
                       std::size_t count, std::vector<float>& lab) {
  const std::size_t capacity = picks.size();
  lab.resize(3 * capacity);
  float* l = lab.data();
  float* a = l + capacity;
  float* b = a + capacity;
  labConverter().convertBatch(cloud.colors.data(), picks.data(), count, l, a, b,
                              detail::LabSimd::Auto);
  return {l, a, b};
}

// Per-pixel features, structure of arrays (the assignment loop streams them).
// Invalid pixels have NaN x/y/z, so every distance to them is NaN and never
// wins a comparison.
enum Channel { kL, kA, kB, kX, kY, kZ, kNX, kNY, kNZ, kNumChannels };

struct FeatureGrid {
  int width = 0;
  int height = 0;
  std::array<std::vector<float>, kNumChannels> ch;

  void resize(int w, int h) {
    width = w;
    height = h;
    for (auto& c : ch) c.assign(static_cast<std::size_t>(w) * h, 0.0f);
  }
  bool valid(std::size_t i) const { return !std::isnan(ch[kZ][i]); }
};

struct Cluster {
  std::array<float, kNumChannels> centre{};
  float u = 0, v = 0;          // centre in coarse pixels
  int half_w = 1, half_h = 1;  // search window half size, coarse pixels
  float nominal_area_px = 0;   // full-resolution pixels of its seed cell
};

struct Weights {
  float color;    // color_importance * kLabScale
  float spatial;  // spatial_importance / seed_resolution
  float normal;   // normal_importance
};

struct SeedRect {  // placeSeeds: a cell of the adaptive seed grid, coarse pixels
  int x0, y0, x1, y1;
};
struct CentreSum {  // updateCentres: sums over a cluster's pixels
  std::array<double, kNumChannels> ch{};
  double u = 0, v = 0;
  int count = 0;
};
struct Pending {  // refineToFullResolution: a boundary pixel's candidate clusters
  std::array<int, 4> candidates;
  int count;
};
struct Run {  // enforceConnectivity: [x0, x1) of one row with one key
  int x0, x1;
  int key;
};
struct Contact {  // enforceConnectivity: border between a small piece and a neighbour
  std::uint64_t pair;  // small << 32 | neighbour
  int length;
};

// The working memory of one segmentInto call, kept per thread between frames
// so that a stream of frames of one size allocates nothing here once warm.
// Each function borrows the vectors it needs for the call (scratch.hpp).
struct OversegBuffers {
  FeatureGrid coarse;
  std::vector<std::uint8_t> block_valid, small;
  std::vector<Cluster> clusters;
  std::vector<float> best;
  std::vector<int> labels, labels_full;
  std::vector<double> density, row_terms;
  std::vector<int> valid;
  std::vector<SeedRect> stack;
  std::vector<CentreSum> sums;
  std::vector<Run> runs;
  std::vector<int> row_begin, parent, run_piece, piece_size, piece_key, merged, target, target_len;
  std::vector<Contact> contacts;
  // buildCoarse, refineToFullResolution: a row's pixels whose colour is
  // wanted, their cells (buildCoarse), candidates (refine) and L, a, b
  std::vector<int> picks, cells;
  std::vector<Pending> pending;
  std::vector<float> lab;
};
thread_local OversegBuffers g_buffers;

using detail::Borrowed;

// For each pixel of rows [y0, y1) x columns [x0, x1): if it is nearer to the
// cluster centre than `best`, take it. (Portable SSE2 version; the AVX one
// below does the same arithmetic eight pixels at a time.)
void assignWindowSse(const FeatureGrid& g, const std::array<float, kNumChannels>& c, const Weights& wt,
                  int label, int x0, int x1, int y0, int y1, float* best, int* labels) {
  const float* ch[kNumChannels];
  for (int k = 0; k < kNumChannels; ++k) ch[k] = g.ch[k].data();
  for (int y = y0; y < y1; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * g.width;
    int x = x0;
#if defined(__SSE2__)
    const __m128 cl = _mm_set1_ps(c[kL]), ca = _mm_set1_ps(c[kA]), cb = _mm_set1_ps(c[kB]);
    const __m128 cx = _mm_set1_ps(c[kX]), cy = _mm_set1_ps(c[kY]), cz = _mm_set1_ps(c[kZ]);
    const __m128 cnx = _mm_set1_ps(c[kNX]), cny = _mm_set1_ps(c[kNY]), cnz = _mm_set1_ps(c[kNZ]);
    const __m128 wc = _mm_set1_ps(wt.color), ws = _mm_set1_ps(wt.spatial),
                 wn = _mm_set1_ps(wt.normal);
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 one = _mm_set1_ps(1.0f);
    const __m128i lab = _mm_set1_epi32(label);
    for (; x + 4 <= x1; x += 4) {
      const std::size_t i = row + x;
      const __m128 dl = _mm_sub_ps(_mm_loadu_ps(ch[kL] + i), cl);
      const __m128 da = _mm_sub_ps(_mm_loadu_ps(ch[kA] + i), ca);
      const __m128 db = _mm_sub_ps(_mm_loadu_ps(ch[kB] + i), cb);
      const __m128 dx = _mm_sub_ps(_mm_loadu_ps(ch[kX] + i), cx);
      const __m128 dy = _mm_sub_ps(_mm_loadu_ps(ch[kY] + i), cy);
      const __m128 dz = _mm_sub_ps(_mm_loadu_ps(ch[kZ] + i), cz);
      const __m128 color2 =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(dl, dl), _mm_mul_ps(da, da)), _mm_mul_ps(db, db));
      const __m128 space2 =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
      const __m128 dot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(ch[kNX] + i), cnx),
                                               _mm_mul_ps(_mm_loadu_ps(ch[kNY] + i), cny)),
                                    _mm_mul_ps(_mm_loadu_ps(ch[kNZ] + i), cnz));
      const __m128 d = _mm_add_ps(
          _mm_add_ps(_mm_mul_ps(wc, _mm_sqrt_ps(color2)), _mm_mul_ps(ws, _mm_sqrt_ps(space2))),
          _mm_mul_ps(wn, _mm_sub_ps(one, _mm_and_ps(dot, abs_mask))));
      const __m128 old = _mm_loadu_ps(best + i);
      const __m128 closer = _mm_cmplt_ps(d, old);  // false for NaN (invalid pixels)
      _mm_storeu_ps(best + i, _mm_or_ps(_mm_and_ps(closer, d), _mm_andnot_ps(closer, old)));
      const __m128i mask = _mm_castps_si128(closer);
      const __m128i old_label = _mm_loadu_si128(reinterpret_cast<const __m128i*>(labels + i));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(labels + i),
                       _mm_or_si128(_mm_and_si128(mask, lab), _mm_andnot_si128(mask, old_label)));
    }
#endif
    for (; x < x1; ++x) {
      const std::size_t i = row + x;
      const float dl = ch[kL][i] - c[kL], da = ch[kA][i] - c[kA], db = ch[kB][i] - c[kB];
      const float dx = ch[kX][i] - c[kX], dy = ch[kY][i] - c[kY], dz = ch[kZ][i] - c[kZ];
      const float dot = ch[kNX][i] * c[kNX] + ch[kNY][i] * c[kNY] + ch[kNZ][i] * c[kNZ];
      const float d = wt.color * std::sqrt(dl * dl + da * da + db * db) +
                      wt.spatial * std::sqrt(dx * dx + dy * dy + dz * dz) +
                      wt.normal * (1.0f - std::fabs(dot));
      if (d < best[i]) {
        best[i] = d;
        labels[i] = label;
      }
    }
  }
}

#if defined(FINDMUG_AVX2_DISPATCH)
// assignWindowSse with 8-wide AVX registers. The same IEEE operations in the
// same order per pixel (no FMA: the target is "avx2", not "fma"), so the
// result is bit-identical to the SSE2 and scalar code; only the lane count
// differs. About 40 % of the oversegmenter's time is this loop.
__attribute__((target("avx2"))) void assignWindowAvx(const FeatureGrid& g,
                                                    const std::array<float, kNumChannels>& c,
                                                    const Weights& wt, int label, int x0, int x1,
                                                    int y0, int y1, float* best, int* labels) {
  const float* ch[kNumChannels];
  for (int k = 0; k < kNumChannels; ++k) ch[k] = g.ch[k].data();
  const __m256 cl = _mm256_set1_ps(c[kL]), ca = _mm256_set1_ps(c[kA]), cb = _mm256_set1_ps(c[kB]);
  const __m256 cx = _mm256_set1_ps(c[kX]), cy = _mm256_set1_ps(c[kY]), cz = _mm256_set1_ps(c[kZ]);
  const __m256 cnx = _mm256_set1_ps(c[kNX]), cny = _mm256_set1_ps(c[kNY]),
               cnz = _mm256_set1_ps(c[kNZ]);
  const __m256 wc = _mm256_set1_ps(wt.color), ws = _mm256_set1_ps(wt.spatial),
               wn = _mm256_set1_ps(wt.normal);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 lab = _mm256_castsi256_ps(_mm256_set1_epi32(label));
  const std::size_t grid_size = static_cast<std::size_t>(g.width) * g.height;
  const __m256i lane_index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (int y = y0; y < y1; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * g.width;
    // A window row is 10-20 pixels wide: the last vector runs past x1 and
    // its extra lanes are masked off (they read pixels beyond the window,
    // inside the grid, and write back what they read), so no pixel takes the
    // scalar path except at the very end of the grid.
    for (int x = x0; x < x1; x += 8) {
      const std::size_t i = row + x;
      if (i + 8 > grid_size) {
        assignWindowSse(g, c, wt, label, x, x1, y, y + 1, best, labels);
        break;
      }
      const __m256 inside = _mm256_castsi256_ps(
          _mm256_cmpgt_epi32(_mm256_set1_epi32(x1 - x), lane_index));
      const __m256 dl = _mm256_sub_ps(_mm256_loadu_ps(ch[kL] + i), cl);
      const __m256 da = _mm256_sub_ps(_mm256_loadu_ps(ch[kA] + i), ca);
      const __m256 db = _mm256_sub_ps(_mm256_loadu_ps(ch[kB] + i), cb);
      const __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(ch[kX] + i), cx);
      const __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(ch[kY] + i), cy);
      const __m256 dz = _mm256_sub_ps(_mm256_loadu_ps(ch[kZ] + i), cz);
      const __m256 color2 = _mm256_add_ps(
          _mm256_add_ps(_mm256_mul_ps(dl, dl), _mm256_mul_ps(da, da)), _mm256_mul_ps(db, db));
      const __m256 space2 = _mm256_add_ps(
          _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
      const __m256 dot =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(ch[kNX] + i), cnx),
                                      _mm256_mul_ps(_mm256_loadu_ps(ch[kNY] + i), cny)),
                        _mm256_mul_ps(_mm256_loadu_ps(ch[kNZ] + i), cnz));
      const __m256 d = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(wc, _mm256_sqrt_ps(color2)),
                                                   _mm256_mul_ps(ws, _mm256_sqrt_ps(space2))),
                                     _mm256_mul_ps(wn, _mm256_sub_ps(one, _mm256_and_ps(dot, abs_mask))));
      const __m256 old = _mm256_loadu_ps(best + i);
      // false for NaN (invalid pixels) and for lanes outside the window
      const __m256 closer = _mm256_and_ps(_mm256_cmp_ps(d, old, _CMP_LT_OQ), inside);
      _mm256_storeu_ps(best + i, _mm256_blendv_ps(old, d, closer));
      float* label_slot = reinterpret_cast<float*>(labels + i);
      _mm256_storeu_ps(label_slot, _mm256_blendv_ps(_mm256_loadu_ps(label_slot), lab, closer));
    }
  }
}

#endif

// updateCentres: the sum of the pixel columns x0 .. x1 - 1 of a run. Sums of
// integers far below 2^53 are exact in any order, so this is the sum pixel
// by pixel, to the bit.
double columnSum(int x0, int x1) {
  return static_cast<double>(static_cast<std::int64_t>(x0 + x1 - 1) * (x1 - x0) / 2);
}

// Adds the channels of pixels [x0, x1) of one row (starting at grid index
// row) to s.ch, one pixel after the other (updateCentres).
void addRunChannels(const float* const* ch, std::size_t row, int x0, int x1, CentreSum& s) {
  double l = s.ch[kL], a = s.ch[kA], b = s.ch[kB];
  double px = s.ch[kX], py = s.ch[kY], pz = s.ch[kZ];
  double nx = s.ch[kNX], ny = s.ch[kNY], nz = s.ch[kNZ];
  for (int x = x0; x < x1; ++x) {
    const std::size_t i = row + x;
    l += ch[kL][i];
    a += ch[kA][i];
    b += ch[kB][i];
    px += ch[kX][i];
    py += ch[kY][i];
    pz += ch[kZ][i];
    nx += ch[kNX][i];
    ny += ch[kNY][i];
    nz += ch[kNZ][i];
  }
  static_assert(kNumChannels == 9 && kL == 0 && kNZ == 8, "channel order of s.ch below");
  s.ch = {l, a, b, px, py, pz, nx, ny, nz};
}

#if defined(FINDMUG_AVX2_DISPATCH)
// addRunChannels four pixels at a time: channels 0-3 and 4-7 of four pixels
// are loaded as rows and transposed, so that one pixel's (L, a, b, x) and
// (y, z, nx, ny) each convert to doubles and add in one instruction; nz goes
// one by one. Each sum still adds the run's pixels one after the other in
// image order (a lane per sum), so the centres are the same bits. Why: the
// scalar loop converts and adds nine floats per pixel one at a time, and
// that, not the additions' latency, bounds it.
__attribute__((target("avx2"))) void addRunChannelsAvx2(const float* const* ch, std::size_t row,
                                                        int x0, int x1, CentreSum& s) {
  static_assert(kL == 0 && kA == 1 && kB == 2 && kX == 3 && kY == 4 && kZ == 5 && kNX == 6 &&
                    kNY == 7 && kNZ == 8,
                "lanes of first and second below");
  __m256d first = _mm256_loadu_pd(s.ch.data());       // L a b x
  __m256d second = _mm256_loadu_pd(s.ch.data() + 4);  // y z nx ny
  double nz = s.ch[kNZ];
  int x = x0;
  for (; x + 4 <= x1; x += 4) {
    const std::size_t i = row + x;
    __m128 p0 = _mm_loadu_ps(ch[0] + i), p1 = _mm_loadu_ps(ch[1] + i);
    __m128 p2 = _mm_loadu_ps(ch[2] + i), p3 = _mm_loadu_ps(ch[3] + i);
    __m128 q0 = _mm_loadu_ps(ch[4] + i), q1 = _mm_loadu_ps(ch[5] + i);
    __m128 q2 = _mm_loadu_ps(ch[6] + i), q3 = _mm_loadu_ps(ch[7] + i);
    _MM_TRANSPOSE4_PS(p0, p1, p2, p3);  // p0 = channels 0-3 of pixel i, p1 of i + 1, ...
    _MM_TRANSPOSE4_PS(q0, q1, q2, q3);
    first = _mm256_add_pd(first, _mm256_cvtps_pd(p0));
    second = _mm256_add_pd(second, _mm256_cvtps_pd(q0));
    nz += ch[kNZ][i];
    first = _mm256_add_pd(first, _mm256_cvtps_pd(p1));
    second = _mm256_add_pd(second, _mm256_cvtps_pd(q1));
    nz += ch[kNZ][i + 1];
    first = _mm256_add_pd(first, _mm256_cvtps_pd(p2));
    second = _mm256_add_pd(second, _mm256_cvtps_pd(q2));
    nz += ch[kNZ][i + 2];
    first = _mm256_add_pd(first, _mm256_cvtps_pd(p3));
    second = _mm256_add_pd(second, _mm256_cvtps_pd(q3));
    nz += ch[kNZ][i + 3];
  }
  _mm256_storeu_pd(s.ch.data(), first);
  _mm256_storeu_pd(s.ch.data() + 4, second);
  s.ch[kNZ] = nz;
  addRunChannels(ch, row, x, x1, s);  // the last pixels
}
#endif

// placeSeeds: the seed density of coarse pixel i, the seeds its surface
// needs (0 where no full pixel of its block is valid).
double seedDensity(const FeatureGrid& coarse, const std::uint8_t* block_valid, std::size_t i,
                   double pixel_solid, double per_seed_area) {
  if (block_valid[i] == 0) return 0.0;
  const float px = coarse.ch[kX][i], py = coarse.ch[kY][i], pz = coarse.ch[kZ][i];
  const float range = std::sqrt(px * px + py * py + pz * pz);
  const float dot = px * coarse.ch[kNX][i] + py * coarse.ch[kNY][i] + pz * coarse.ch[kNZ][i];
  const bool has_normal =
      coarse.ch[kNX][i] != 0.0f || coarse.ch[kNY][i] != 0.0f || coarse.ch[kNZ][i] != 0.0f;
  const float cosine = has_normal ? std::max(std::fabs(dot) / range, kMinCosine) : 1.0f;
  const double footprint = std::min(static_cast<double>(pz) * pz / cosine, kMaxFootprint);
  return block_valid[i] * footprint * pixel_solid / per_seed_area;
}

#if defined(FINDMUG_AVX2_DISPATCH)
// seedDensity of coarse pixels first .. first + 7 into out[0..7]: the same
// float and double operations as lanes (std::max and std::min as max/min
// with the operands in the order that returns a NaN first operand, as they
// do). Its square root and three divisions per pixel were most of
// placeSeeds' time one pixel at a time.
__attribute__((target("avx2"))) void seedDensity8(const FeatureGrid& coarse,
                                                  const std::uint8_t* block_valid,
                                                  std::size_t first, double pixel_solid,
                                                  double per_seed_area, double* out) {
  const __m256 px = _mm256_loadu_ps(coarse.ch[kX].data() + first);
  const __m256 py = _mm256_loadu_ps(coarse.ch[kY].data() + first);
  const __m256 pz = _mm256_loadu_ps(coarse.ch[kZ].data() + first);
  const __m256 nx = _mm256_loadu_ps(coarse.ch[kNX].data() + first);
  const __m256 ny = _mm256_loadu_ps(coarse.ch[kNY].data() + first);
  const __m256 nz = _mm256_loadu_ps(coarse.ch[kNZ].data() + first);
  const __m256 range = _mm256_sqrt_ps(_mm256_add_ps(
      _mm256_add_ps(_mm256_mul_ps(px, px), _mm256_mul_ps(py, py)), _mm256_mul_ps(pz, pz)));
  const __m256 dot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(px, nx), _mm256_mul_ps(py, ny)),
                                   _mm256_mul_ps(pz, nz));
  const __m256 zero = _mm256_setzero_ps();
  const __m256 has_normal = _mm256_or_ps(
      _mm256_or_ps(_mm256_cmp_ps(nx, zero, _CMP_NEQ_UQ), _mm256_cmp_ps(ny, zero, _CMP_NEQ_UQ)),
      _mm256_cmp_ps(nz, zero, _CMP_NEQ_UQ));
  const __m256 abs_dot = _mm256_and_ps(dot, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff)));
  // std::max(a, m) = a < m ? m : a: max_ps(m, a) = m > a ? m : a.
  const __m256 slant = _mm256_max_ps(_mm256_set1_ps(kMinCosine), _mm256_div_ps(abs_dot, range));
  const __m256 cosine = _mm256_blendv_ps(_mm256_set1_ps(1.0f), slant, has_normal);
  const __m256i valid_bytes = _mm256_cvtepu8_epi32(
      _mm_loadl_epi64(reinterpret_cast<const __m128i*>(block_valid + first)));
  for (int half = 0; half < 2; ++half) {
    const __m128 pz4 = half == 0 ? _mm256_castps256_ps128(pz) : _mm256_extractf128_ps(pz, 1);
    const __m128 cos4 =
        half == 0 ? _mm256_castps256_ps128(cosine) : _mm256_extractf128_ps(cosine, 1);
    const __m128i valid4 = half == 0 ? _mm256_castsi256_si128(valid_bytes)
                                     : _mm256_extracti128_si256(valid_bytes, 1);
    const __m256d pzd = _mm256_cvtps_pd(pz4);
    // std::min(f, k) = k < f ? k : f: min_pd(k, f) = k < f ? k : f.
    const __m256d footprint =
        _mm256_min_pd(_mm256_set1_pd(kMaxFootprint),
                      _mm256_div_pd(_mm256_mul_pd(pzd, pzd), _mm256_cvtps_pd(cos4)));
    const __m256d count = _mm256_cvtepi32_pd(valid4);
    const __m256d density = _mm256_div_pd(
        _mm256_mul_pd(_mm256_mul_pd(count, footprint), _mm256_set1_pd(pixel_solid)),
        _mm256_set1_pd(per_seed_area));
    // Pixels without a valid full pixel: 0, as seedDensity.
    const __m256d none = _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_cvtepi32_epi64(valid4),
                                                                _mm256_setzero_si256()));
    _mm256_storeu_pd(out + 4 * half, _mm256_andnot_pd(none, density));
  }
}
#endif

// `avx2`: assignWindowAvx when the CPU has AVX2, the SSE2 loop otherwise
// (the tests compare the two: OversegSimd::Off).
void assignWindow(const FeatureGrid& g, const std::array<float, kNumChannels>& c, const Weights& wt,
                  int label, int x0, int x1, int y0, int y1, float* best, int* labels,
                  bool avx2) {
#if defined(FINDMUG_AVX2_DISPATCH)
  if (avx2) {
    assignWindowAvx(g, c, wt, label, x0, x1, y0, y1, best, labels);
    return;
  }
#else
  (void)avx2;
#endif
  assignWindowSse(g, c, wt, label, x0, x1, y0, y1, best, labels);
}

float featureDistance(const FeatureGrid& g, std::size_t i, std::size_t j, const Weights& wt) {
  const auto& c = g.ch;
  const float dl = c[kL][i] - c[kL][j], da = c[kA][i] - c[kA][j], db = c[kB][i] - c[kB][j];
  const float dx = c[kX][i] - c[kX][j], dy = c[kY][i] - c[kY][j], dz = c[kZ][i] - c[kZ][j];
  const float dot = c[kNX][i] * c[kNX][j] + c[kNY][i] * c[kNY][j] + c[kNZ][i] * c[kNZ][j];
  return wt.color * std::sqrt(dl * dl + da * da + db * db) +
         wt.spatial * std::sqrt(dx * dx + dy * dy + dz * dz) + wt.normal * (1.0f - std::fabs(dot));
}

// Focal length along one image axis from the points themselves: for a
// pinhole camera, pixel coordinate = f * (x/z) + c, a line. Least squares
// over a subsample; returns NaN when the valid points span one column (row).
double estimateFocal(const OrganizedCloud& cloud, bool along_x) {
  double n = 0, sa = 0, su = 0, saa = 0, sau = 0;
  constexpr int kStep = 4;
  for (int y = 0; y < cloud.height; y += kStep) {
    for (int x = 0; x < cloud.width; x += kStep) {
      const std::size_t i = static_cast<std::size_t>(y) * cloud.width + x;
      const Eigen::Vector3f& p = cloud.points[i];
      if (!(p.z() > 0.0f) || !std::isfinite(p.x()) || !std::isfinite(p.y())) continue;
      const double a = (along_x ? p.x() : p.y()) / p.z();
      const double u = along_x ? x : y;
      n += 1;
      sa += a;
      su += u;
      saa += a * a;
      sau += a * u;
    }
  }
  const double var = saa - sa * sa / std::max(n, 1.0);
  if (n < 2 || !(var > 1e-12 * std::max(n, 1.0))) return std::numeric_limits<double>::quiet_NaN();
  const double f = (sau - sa * su / n) / var;
  return f > 0 && std::isfinite(f) ? f : std::numeric_limits<double>::quiet_NaN();
}

#if defined(FINDMUG_AVX2_DISPATCH)
// refineToFullResolution's first test for full pixels x0..x0+7 of a row
// (x0 even, 2 <= x0, x0 + 8 <= width, x0 / 2 + 7 <= coarse width): `points`
// is the row's first point, row_a and row_b the two coarse label rows. Pixel
// x's samples are coarse columns x / 2 and x / 2 - 1 (x even) or x / 2 + 1
// (x odd), in both rows. Writes out[x0..x0+7] for the lanes that are not
// usable (-1) or whose four samples agree (their label, or kUnassigned), as
// the scalar code does, and returns the mask of the other lanes (usable,
// samples differ), which the scalar code then decides one by one.
__attribute__((target("avx2"))) int refineBlockAvx2(const Eigen::Vector3f* points,
                                                   const int* row_a, const int* row_b, int x0,
                                                   int* out) {
  const int c = x0 / 2;
  // Coarse columns c-1 .. c+6; the lanes use c-1 .. c+4.
  const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row_a + c - 1));
  const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row_b + c - 1));
  const __m256i own = _mm256_setr_epi32(1, 1, 2, 2, 3, 3, 4, 4);    // x / 2
  const __m256i other = _mm256_setr_epi32(0, 2, 1, 3, 2, 4, 3, 5);  // x / 2 -+ 1
  const __m256i a0 = _mm256_permutevar8x32_epi32(a, own);
  const __m256i agree = _mm256_and_si256(
      _mm256_and_si256(_mm256_cmpeq_epi32(a0, _mm256_permutevar8x32_epi32(a, other)),
                       _mm256_cmpeq_epi32(a0, _mm256_permutevar8x32_epi32(b, own))),
      _mm256_cmpeq_epi32(a0, _mm256_permutevar8x32_epi32(b, other)));
  // usable(): z > 0 and every coordinate finite (|v| < inf, false for NaN).
  __m256 x, y, z;
  detail::loadVec3x8(points[x0].data(), x, y, z);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 finite_x = _mm256_cmp_ps(_mm256_and_ps(x, abs_mask), inf, _CMP_LT_OQ);
  const __m256 finite_y = _mm256_cmp_ps(_mm256_and_ps(y, abs_mask), inf, _CMP_LT_OQ);
  const __m256 finite_z = _mm256_cmp_ps(_mm256_and_ps(z, abs_mask), inf, _CMP_LT_OQ);
  const __m256i usable = _mm256_castps_si256(
      _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(z, _mm256_setzero_ps(), _CMP_GT_OQ), finite_x),
                    _mm256_and_ps(finite_y, finite_z)));
  const __m256i label = _mm256_blendv_epi8(_mm256_set1_epi32(kUnassigned), a0,
                                           _mm256_cmpgt_epi32(a0, _mm256_set1_epi32(-1)));
  const __m256i decided = _mm256_and_si256(usable, agree);
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + x0),
                      _mm256_blendv_epi8(_mm256_set1_epi32(-1), label, decided));
  return _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_andnot_si256(agree, usable)));
}
#endif

class OrganizedOversegmenter final : public Oversegmenter {
 public:
  // `simd`: detail::OversegSimd::Off keeps to the scalar refinement (tests).
  explicit OrganizedOversegmenter(const OversegmentationConfig& config,
                                  detail::OversegSimd simd = detail::OversegSimd::Auto)
      : config_(config), simd_(simd) {
    weights_.color = config.color_importance * kLabScale;
    weights_.spatial = config.spatial_importance / config.seed_resolution_m;
    weights_.normal = config.normal_importance;
  }

  std::string name() const override { return "organized"; }

  Oversegmentation segment(const OrganizedCloud& cloud, const NormalImage& normals) const override {
    Oversegmentation seg;
    segmentInto(cloud, normals, seg);
    return seg;
  }

  void segmentInto(const OrganizedCloud& cloud, const NormalImage& normals,
                   Oversegmentation& seg) const override {
    detail::checkOversegmentationInput(cloud, normals, "organized oversegmenter");
    const int w = cloud.width;
    const int h = cloud.height;
    const std::size_t n = cloud.size();

    seg.width = w;
    seg.height = h;
    // Every pixel is written below (enforceConnectivity), or here when no
    // pixel is usable.
    seg.pixel_segment.resize(n);

    // Working buffers: this thread's from earlier frames (see OversegBuffers).
    // Half-resolution features; a pixel is usable when it has a point in
    // front of the camera (z <= 0 cannot come from one).
    Borrowed coarse_buffer(g_buffers.coarse);
    FeatureGrid& coarse = *coarse_buffer;
    Borrowed block_valid_buffer(g_buffers.block_valid);
    std::vector<std::uint8_t>& block_valid = *block_valid_buffer;  // usable full pixels per coarse pixel
    if (buildCoarse(cloud, normals, coarse, block_valid) == 0) {
      std::fill(seg.pixel_segment.begin(), seg.pixel_segment.end(), -1);
      finalizeOversegmentation(seg, config_.min_segment_points);
      return;
    }

    Borrowed clusters_buffer(g_buffers.clusters);
    std::vector<Cluster>& clusters = *clusters_buffer;
    placeSeeds(cloud, coarse, block_valid, clusters);

    // Iterations on the coarse grid.
    const std::size_t nc = static_cast<std::size_t>(coarse.width) * coarse.height;
    Borrowed best_buffer(g_buffers.best);
    std::vector<float>& best = *best_buffer;
    best.resize(nc);
    Borrowed labels_buffer(g_buffers.labels);
    std::vector<int>& labels = *labels_buffer;
    labels.resize(nc);
    const bool iterate_avx2 = useAvx2();  // window search and centre sums
    for (int iter = 0; iter < config_.max_iterations; ++iter) {
      std::fill(best.begin(), best.end(), std::numeric_limits<float>::infinity());
      std::fill(labels.begin(), labels.end(), -1);
      for (std::size_t k = 0; k < clusters.size(); ++k) {
        const Cluster& c = clusters[k];
        const int cu = static_cast<int>(std::lround(c.u));
        const int cv = static_cast<int>(std::lround(c.v));
        assignWindow(coarse, c.centre, weights_, static_cast<int>(k), std::max(0, cu - c.half_w),
                     std::min(coarse.width, cu + c.half_w + 1), std::max(0, cv - c.half_h),
                     std::min(coarse.height, cv + c.half_h + 1), best.data(), labels.data(),
                     iterate_avx2);
      }
      updateCentres(coarse, labels, clusters, iterate_avx2);
    }

    Borrowed labels_full_buffer(g_buffers.labels_full);
    std::vector<int>& labels_full = *labels_full_buffer;
    refineToFullResolution(cloud, normals, coarse, labels, clusters, labels_full);
    enforceConnectivity(w, h, clusters, labels_full, seg.pixel_segment);
    finalizeOversegmentation(seg, config_.min_segment_points);
  }

 private:
  static bool usable(const Eigen::Vector3f& p) { return p.z() > 0.0f && p.allFinite(); }

  // Point and normal channels (kX..kNZ) of full-resolution pixel i (usable)
  // into f.
  static void pointAndNormal(const OrganizedCloud& cloud, const NormalImage& normals,
                             std::size_t i, std::array<float, kNumChannels>& f) {
    const Eigen::Vector3f& p = cloud.points[i];
    f[kX] = p.x();
    f[kY] = p.y();
    f[kZ] = p.z();
    // No normal: a zero vector makes the normal term the same (1) for every
    // cluster, so the others decide.
    const Eigen::Vector3f& nv = normals.normals[i];
    const bool has_normal = nv.allFinite();
    f[kNX] = has_normal ? nv.x() : 0.0f;
    f[kNY] = has_normal ? nv.y() : 0.0f;
    f[kNZ] = has_normal ? nv.z() : 0.0f;
  }

  float distance(const std::array<float, kNumChannels>& f,
                 const std::array<float, kNumChannels>& c) const {
    const float dl = f[kL] - c[kL], da = f[kA] - c[kA], db = f[kB] - c[kB];
    const float dx = f[kX] - c[kX], dy = f[kY] - c[kY], dz = f[kZ] - c[kZ];
    const float dot = f[kNX] * c[kNX] + f[kNY] * c[kNY] + f[kNZ] * c[kNZ];
    return weights_.color * std::sqrt(dl * dl + da * da + db * db) +
           weights_.spatial * std::sqrt(dx * dx + dy * dy + dz * dz) +
           weights_.normal * (1.0f - std::fabs(dot));
  }

  // distance(f, centre of clusters[candidates[c]]) into d[c] for c < count
  // (2..4): one SSE2 lane per candidate, the same operations in the same
  // order as distance(), so the same values.
  void candidateDistances(const std::array<float, kNumChannels>& f,
                          const std::vector<Cluster>& clusters, const std::array<int, 4>& candidates,
                          int count, std::array<float, 4>& d) const {
#if defined(__SSE2__)
    const float* c0 = clusters[candidates[0]].centre.data();
    const float* c1 = clusters[candidates[1]].centre.data();
    const float* c2 = count > 2 ? clusters[candidates[2]].centre.data() : c0;
    const float* c3 = count > 3 ? clusters[candidates[3]].centre.data() : c0;
    const auto diff = [&](int k) {
      return _mm_sub_ps(_mm_set1_ps(f[k]), _mm_setr_ps(c0[k], c1[k], c2[k], c3[k]));
    };
    const auto times = [&](int k) {
      return _mm_mul_ps(_mm_set1_ps(f[k]), _mm_setr_ps(c0[k], c1[k], c2[k], c3[k]));
    };
    const __m128 dl = diff(kL), da = diff(kA), db = diff(kB);
    const __m128 dx = diff(kX), dy = diff(kY), dz = diff(kZ);
    const __m128 color2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dl, dl), _mm_mul_ps(da, da)), _mm_mul_ps(db, db));
    const __m128 space2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 dot = _mm_add_ps(_mm_add_ps(times(kNX), times(kNY)), times(kNZ));
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 result = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(_mm_set1_ps(weights_.color), _mm_sqrt_ps(color2)),
                   _mm_mul_ps(_mm_set1_ps(weights_.spatial), _mm_sqrt_ps(space2))),
        _mm_mul_ps(_mm_set1_ps(weights_.normal),
                   _mm_sub_ps(_mm_set1_ps(1.0f), _mm_and_ps(dot, abs_mask))));
    _mm_storeu_ps(d.data(), result);
#else
    for (int c = 0; c < count; ++c) d[c] = distance(f, clusters[candidates[c]].centre);
#endif
  }

  // Full-resolution labels from the coarse ones. A pixel lies between the
  // (up to) 2x2 coarse samples nearest to it; where they agree it takes
  // their label, along boundaries it picks the nearest of their clusters.
  // Pixels with no labelled sample around are kUnassigned, unusable ones -1.
  // Only boundary pixels need their own features, which is most of the
  // saving over a full-resolution SLIC pass.
  void refineToFullResolution(const OrganizedCloud& cloud, const NormalImage& normals,
                              const FeatureGrid& coarse, const std::vector<int>& labels,
                              const std::vector<Cluster>& clusters, std::vector<int>& out) const {
    const int w = cloud.width;
    const int h = cloud.height;
    const int cw = coarse.width;
    const int chh = coarse.height;
    out.resize(cloud.size());  // every pixel is written below, once
    std::array<float, kNumChannels> f{};
    // The sample of coarse pixel c is (usually) full pixel 2c: an even pixel
    // sits on it (its other neighbour is c - 1), an odd one between c, c + 1.
    const auto other = [](int full, int c, int size) {
      return std::clamp(full % kCoarseStride == 0 ? c - 1 : c + 1, 0, size - 1);
    };
    // A row's boundary pixels wait here until their colours have been
    // converted together (eight at a time with AVX2).
    Borrowed pending_buffer(g_buffers.pending);
    std::vector<Pending>& pending = *pending_buffer;
    Borrowed picks_buffer(g_buffers.picks);
    std::vector<int>& picks = *picks_buffer;
    Borrowed lab_buffer(g_buffers.lab);
    std::vector<float>& lab = *lab_buffer;
    pending.resize(w);
    picks.resize(w);
#if defined(FINDMUG_AVX2_DISPATCH)
    const bool avx2 = useAvx2();
#endif
    for (int y = 0; y < h; ++y) {
      std::size_t waiting = 0;
      const int cy = y / kCoarseStride;
      const int* row_a = labels.data() + static_cast<std::size_t>(cy) * cw;
      const int* row_b = labels.data() + static_cast<std::size_t>(other(y, cy, chh)) * cw;
      // The scalar decision for pixel x of this row.
      const auto refinePixel = [&](int x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        if (!usable(cloud.points[i])) {
          out[i] = -1;
          return;
        }
        const int cx = x / kCoarseStride;
        const int ox = other(x, cx, cw);
        const std::array<int, 4> around = {row_a[cx], row_a[ox], row_b[cx], row_b[ox]};
        // Inside a segment (most pixels) the four agree: no search.
        if (around[0] == around[1] && around[0] == around[2] && around[0] == around[3]) {
          out[i] = around[0] >= 0 ? around[0] : kUnassigned;
          return;
        }
        std::array<int, 4> candidates{};
        int count = 0;
        for (const int k : around) {
          if (k >= 0 && std::find(candidates.begin(), candidates.begin() + count, k) ==
                            candidates.begin() + count) {
            candidates[count++] = k;
          }
        }
        if (count <= 1) {
          out[i] = count == 1 ? candidates[0] : kUnassigned;
          return;
        }
        pending[waiting] = {candidates, count};
        picks[waiting] = static_cast<int>(i);
        // Nothing else in this pass reads the normal and colour images, so a
        // boundary pixel's normal and colour were cache misses when the
        // distances below read them (a third of the refinement's time on the
        // synthetic walk): ask for them now, while the row is scanned.
        __builtin_prefetch(normals.normals.data() + i);
        __builtin_prefetch(cloud.colors.data() + i);
        ++waiting;
      };
      int x = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
      if (avx2) {
        // Eight pixels at a time where the block's samples stay inside the
        // coarse row; the lanes whose samples differ go to refinePixel, in
        // order, so `pending` is the same list as pixel by pixel.
        const Eigen::Vector3f* row_points = cloud.points.data() + static_cast<std::size_t>(y) * w;
        int* row_out = out.data() + static_cast<std::size_t>(y) * w;
        for (; x < 2; ++x) refinePixel(x);
        for (; x + 8 <= w && x / 2 + 7 <= cw; x += 8) {
          for (int left = refineBlockAvx2(row_points, row_a, row_b, x, row_out); left != 0;
               left &= left - 1) {
            refinePixel(x + __builtin_ctz(static_cast<unsigned>(left)));
          }
        }
      }
#endif
      for (; x < w; ++x) refinePixel(x);
      const LabPlanes colour = convertPicks(cloud, picks, waiting, lab);
      for (std::size_t j = 0; j < waiting; ++j) {
        const Pending& p = pending[j];
        f[kL] = colour.l[j];
        f[kA] = colour.a[j];
        f[kB] = colour.b[j];
        pointAndNormal(cloud, normals, static_cast<std::size_t>(picks[j]), f);
        std::array<float, 4> d{};
        candidateDistances(f, clusters, p.candidates, p.count, d);
        int best_k = p.candidates[0];
        float best_d = d[0];
        for (int c = 1; c < p.count; ++c) {
          if (d[c] < best_d) {
            best_d = d[c];
            best_k = p.candidates[c];
          }
        }
        out[static_cast<std::size_t>(picks[j])] = best_k;
      }
    }
  }

  // One usable pixel per 2x2 block (not the mean: a mean across a depth
  // edge is a point in mid-air). Returns the number of usable full pixels.
  static std::size_t buildCoarse(const OrganizedCloud& cloud, const NormalImage& normals,
                                 FeatureGrid& coarse, std::vector<std::uint8_t>& block_valid) {
    const int w = cloud.width;
    const int h = cloud.height;
    const int cw = (w + kCoarseStride - 1) / kCoarseStride;
    const int chh = (h + kCoarseStride - 1) / kCoarseStride;
    coarse.resize(cw, chh);
    block_valid.assign(static_cast<std::size_t>(cw) * chh, 0);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::size_t total = 0;
    std::array<float, kNumChannels> f{};
    // The colours of a row's picks are converted together (eight at a time
    // with AVX2), then scattered to their cells.
    Borrowed picks_buffer(g_buffers.picks);
    std::vector<int>& picks = *picks_buffer;
    Borrowed cells_buffer(g_buffers.cells);
    std::vector<int>& cells = *cells_buffer;
    Borrowed lab_buffer(g_buffers.lab);
    std::vector<float>& lab = *lab_buffer;
    picks.resize(cw);
    cells.resize(cw);
    for (int cy = 0; cy < chh; ++cy) {
      std::size_t picked = 0;
      for (int cx = 0; cx < cw; ++cx) {
        const std::size_t ci = static_cast<std::size_t>(cy) * cw + cx;
        std::size_t pick = 0;
        int count = 0;
        for (int y = cy * kCoarseStride; y < std::min(h, (cy + 1) * kCoarseStride); ++y) {
          for (int x = cx * kCoarseStride; x < std::min(w, (cx + 1) * kCoarseStride); ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * w + x;
            if (!usable(cloud.points[i])) continue;
            if (count == 0) pick = i;
            ++count;
          }
        }
        block_valid[ci] = static_cast<std::uint8_t>(count);
        total += count;
        if (count == 0) {
          coarse.ch[kX][ci] = coarse.ch[kY][ci] = coarse.ch[kZ][ci] = nan;
          continue;
        }
        pointAndNormal(cloud, normals, pick, f);
        for (int k = kX; k < kNumChannels; ++k) coarse.ch[k][ci] = f[k];
        picks[picked] = static_cast<int>(pick);
        cells[picked] = static_cast<int>(ci);
        ++picked;
      }
      const LabPlanes colour = convertPicks(cloud, picks, picked, lab);
      for (std::size_t j = 0; j < picked; ++j) {
        coarse.ch[kL][cells[j]] = colour.l[j];
        coarse.ch[kA][cells[j]] = colour.a[j];
        coarse.ch[kB][cells[j]] = colour.b[j];
      }
    }
    return total;
  }

  // The seeds, into `clusters` (whatever it held before).
  void placeSeeds(const OrganizedCloud& cloud, const FeatureGrid& coarse,
                  const std::vector<std::uint8_t>& block_valid, std::vector<Cluster>& clusters) const {
    clusters.clear();
    double fx = estimateFocal(cloud, true);
    double fy = estimateFocal(cloud, false);
    if (std::isnan(fx)) fx = fy;  // square pixels when one axis cannot tell
    if (std::isnan(fy)) fy = fx;
    if (std::isnan(fx)) return;  // valid points in a single pixel: no segment

    // Seeds per full-resolution pixel = surface area / area per seed.
    const int cw = coarse.width;
    const int chh = coarse.height;
    const double per_seed_area = static_cast<double>(config_.seed_resolution_m) *
                                 config_.seed_resolution_m / config_.organized_seed_density;
    const double pixel_solid = 1.0 / (fx * fy);
    // Integral images (cw+1)x(chh+1) of seed density and of valid pixels.
    Borrowed density_buffer(g_buffers.density);
    std::vector<double>& density = *density_buffer;
    density.assign((cw + 1) * static_cast<std::size_t>(chh + 1), 0.0);
    Borrowed valid_buffer(g_buffers.valid);
    std::vector<int>& valid = *valid_buffer;
    valid.assign((cw + 1) * static_cast<std::size_t>(chh + 1), 0);
    const auto at = [cw](int x, int y) { return static_cast<std::size_t>(y) * (cw + 1) + x; };
    // Each row's densities first (eight at a time with AVX2), then its
    // running sums in order. A pixel without a valid full pixel adds +0,
    // which leaves the sum (never -0) as it is.
    Borrowed row_terms_buffer(g_buffers.row_terms);
    std::vector<double>& row_terms = *row_terms_buffer;
    row_terms.resize(static_cast<std::size_t>(cw));
#if defined(FINDMUG_AVX2_DISPATCH)
    const bool avx2 = useAvx2();
#endif
    for (int y = 0; y < chh; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * cw;
      int x = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
      if (avx2) {
        for (; x + 8 <= cw; x += 8) {
          seedDensity8(coarse, block_valid.data(), row + x, pixel_solid, per_seed_area,
                       row_terms.data() + x);
        }
      }
#endif
      for (; x < cw; ++x) {
        row_terms[x] = seedDensity(coarse, block_valid.data(), row + x, pixel_solid, per_seed_area);
      }
      double row_density = 0;
      int row_valid = 0;
      for (x = 0; x < cw; ++x) {
        row_density += row_terms[x];
        row_valid += block_valid[row + x] > 0 ? 1 : 0;
        density[at(x + 1, y + 1)] = density[at(x + 1, y)] + row_density;
        valid[at(x + 1, y + 1)] = valid[at(x + 1, y)] + row_valid;
      }
    }
    const auto rectSum = [&at](const auto& integral, int x0, int y0, int x1, int y1) {
      return integral[at(x1, y1)] - integral[at(x0, y1)] - integral[at(x1, y0)] +
             integral[at(x0, y0)];
    };

    // Coarse pixels a seed needs: its segment would be dropped otherwise.
    const int min_valid = std::max(1, config_.min_segment_points / (kCoarseStride * kCoarseStride));
    const float half_factor = 0.5f * static_cast<float>(config_.search_window_factor);
    Borrowed stack_buffer(g_buffers.stack);
    std::vector<SeedRect>& stack = *stack_buffer;
    stack.assign(1, SeedRect{0, 0, cw, chh});
    while (!stack.empty()) {
      const SeedRect r = stack.back();
      stack.pop_back();
      const int rw = r.x1 - r.x0;
      const int rh = r.y1 - r.y0;
      const int nvalid = rectSum(valid, r.x0, r.y0, r.x1, r.y1);
      if (nvalid < min_valid) continue;
      // This cell deserves round(D) seeds. Cut its longer side so that the
      // parts get floor(k/2) and ceil(k/2) of them: the count follows the
      // density smoothly (halving alone would give power-of-two cells whose
      // count jumps by 2x where the density is uniform).
      const double seeds = rectSum(density, r.x0, r.y0, r.x1, r.y1);
      const long k = std::lround(seeds);
      // Parts must still be able to hold a segment that survives.
      if (k >= 2 && std::max(rw, rh) >= 2 && rw * rh >= 2 * min_valid) {
        const double share = static_cast<double>(k / 2) / static_cast<double>(k) * seeds;
        const bool cut_x = rw >= rh;
        const int lo = cut_x ? r.x0 : r.y0;
        const int hi = cut_x ? r.x1 : r.y1;
        const auto before = [&](int cut) {
          return cut_x ? rectSum(density, r.x0, r.y0, cut, r.y1)
                       : rectSum(density, r.x0, r.y0, r.x1, cut);
        };
        // Smallest cut in (lo, hi) with at least `share` before it.
        int a = lo + 1, b = hi - 1;
        while (a < b) {
          const int mid = a + (b - a) / 2;
          if (before(mid) >= share) {
            b = mid;
          } else {
            a = mid + 1;
          }
        }
        int cut = a;
        if (cut - 1 > lo && share - before(cut - 1) < before(cut) - share) --cut;
        if (cut_x) {
          stack.push_back({r.x0, r.y0, cut, r.y1});
          stack.push_back({cut, r.y0, r.x1, r.y1});
        } else {
          stack.push_back({r.x0, r.y0, r.x1, cut});
          stack.push_back({r.x0, cut, r.x1, r.y1});
        }
        continue;
      }
      const std::size_t seed = seedPixel(coarse, r.x0, r.y0, r.x1, r.y1);
      Cluster c;
      for (int k = 0; k < kNumChannels; ++k) c.centre[k] = coarse.ch[k][seed];
      c.u = static_cast<float>(seed % cw);
      c.v = static_cast<float>(seed / cw);
      // Window: factor x the cell, but at least factor x its equivalent
      // square side along each axis, so a narrow cell can still move.
      const float side = std::sqrt(static_cast<float>(rw) * static_cast<float>(rh));
      c.half_w = std::max(1, static_cast<int>(std::ceil(half_factor * std::max<float>(rw, side))));
      c.half_h = std::max(1, static_cast<int>(std::ceil(half_factor * std::max<float>(rh, side))));
      c.nominal_area_px = static_cast<float>(rw) * rh * kCoarseStride * kCoarseStride;
      clusters.push_back(c);
    }
  }

  // The valid pixel nearest the cell centre, moved to the lowest-gradient
  // pixel of its 3x3 neighbourhood so that seeds avoid edges.
  std::size_t seedPixel(const FeatureGrid& g, int x0, int y0, int x1, int y1) const {
    const float mx = 0.5f * static_cast<float>(x0 + x1 - 1);
    const float my = 0.5f * static_cast<float>(y0 + y1 - 1);
    std::size_t nearest = 0;
    float nearest_d2 = std::numeric_limits<float>::infinity();
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
        if (!g.valid(i)) continue;
        const float d2 = (x - mx) * (x - mx) + (y - my) * (y - my);
        if (d2 < nearest_d2) {
          nearest_d2 = d2;
          nearest = i;
        }
      }
    }
    const int nx = static_cast<int>(nearest % g.width);
    const int ny = static_cast<int>(nearest / g.width);
    std::size_t chosen = nearest;
    float chosen_gradient = gradient(g, nx, ny);
    for (int y = std::max(0, ny - 1); y <= std::min(g.height - 1, ny + 1); ++y) {
      for (int x = std::max(0, nx - 1); x <= std::min(g.width - 1, nx + 1); ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
        if (!g.valid(i)) continue;
        const float grad = gradient(g, x, y);
        if (grad < chosen_gradient) {
          chosen_gradient = grad;
          chosen = i;
        }
      }
    }
    return chosen;
  }

  // Central-difference feature gradient; infinite next to invalid pixels or
  // the image border (no seed on the rim of a hole).
  float gradient(const FeatureGrid& g, int x, int y) const {
    if (x <= 0 || y <= 0 || x + 1 >= g.width || y + 1 >= g.height) {
      return std::numeric_limits<float>::infinity();
    }
    const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
    const std::size_t l = i - 1, r = i + 1, u = i - g.width, d = i + g.width;
    if (!g.valid(l) || !g.valid(r) || !g.valid(u) || !g.valid(d)) {
      return std::numeric_limits<float>::infinity();
    }
    return featureDistance(g, l, r, weights_) + featureDistance(g, u, d, weights_);
  }

  // `avx2`: the channel sums four pixels at a time (the same bits).
  static void updateCentres(const FeatureGrid& g, const std::vector<int>& labels,
                            std::vector<Cluster>& clusters, bool avx2) {
    Borrowed sums_buffer(g_buffers.sums);
    std::vector<CentreSum>& sums = *sums_buffer;
    sums.assign(clusters.size(), CentreSum{});
    const float* ch[kNumChannels];
    for (int c = 0; c < kNumChannels; ++c) ch[c] = g.ch[c].data();
    // A row holds a few runs of one cluster each: a run's sums are added in
    // locals (registers), then stored. Per cluster the additions happen in
    // the same order as pixel by pixel, so the centres are the same bits;
    // through sums[k] every pixel cost a load and a store per sum.
    for (int y = 0; y < g.height; ++y) {
      const int* row = labels.data() + static_cast<std::size_t>(y) * g.width;
      for (int x = 0; x < g.width;) {
        const int k = row[x];
        int x1 = x + 1;
        while (x1 < g.width && row[x1] == k) ++x1;
        if (k >= 0) {
          CentreSum& sum = sums[k];
          const std::size_t row_start = static_cast<std::size_t>(y) * g.width;
#if defined(FINDMUG_AVX2_DISPATCH)
          if (avx2) {
            addRunChannelsAvx2(ch, row_start, x, x1, sum);
          } else {
            addRunChannels(ch, row_start, x, x1, sum);
          }
#else
          (void)avx2;
          addRunChannels(ch, row_start, x, x1, sum);
#endif
          // Sums of pixel coordinates are integers far below 2^53, exact
          // in any order: whole runs at once.
          sum.u += columnSum(x, x1);
          sum.v += static_cast<double>(y) * (x1 - x);
          sum.count += x1 - x;
        }
        x = x1;
      }
    }
    for (std::size_t k = 0; k < clusters.size(); ++k) {
      const CentreSum& s = sums[k];
      if (s.count == 0) continue;  // keeps its old centre; may win pixels next round
      Cluster& c = clusters[k];
      const double inv = 1.0 / s.count;
      for (int ch = 0; ch < kNumChannels; ++ch) c.centre[ch] = static_cast<float>(s.ch[ch] * inv);
      const float norm = std::sqrt(c.centre[kNX] * c.centre[kNX] + c.centre[kNY] * c.centre[kNY] +
                                   c.centre[kNZ] * c.centre[kNZ]);
      if (norm > 1e-6f) {
        c.centre[kNX] /= norm;
        c.centre[kNY] /= norm;
        c.centre[kNZ] /= norm;
      }
      c.u = static_cast<float>(s.u * inv);
      c.v = static_cast<float>(s.v * inv);
    }
  }

  // Splits every label into its 4-connected pieces and merges small pieces
  // (and usable pixels no cluster reached) into the neighbouring piece they
  // share the longest border with. Writes one id per piece group into `out`.
  // Works on horizontal runs of equal key (a few tens per row) rather than
  // on pixels.
  // `key`: cluster per pixel, kUnassigned, or -1 (unusable: in no piece).
  void enforceConnectivity(int w, int h, const std::vector<Cluster>& clusters,
                           const std::vector<int>& key, std::vector<int>& out) const {
    Borrowed runs_buffer(g_buffers.runs);
    std::vector<Run>& runs = *runs_buffer;
    Borrowed row_begin_buffer(g_buffers.row_begin);
    std::vector<int>& row_begin = *row_begin_buffer;
    findKeyRuns(w, h, key, runs, row_begin);

    Borrowed run_piece_buffer(g_buffers.run_piece);
    std::vector<int>& run_piece = *run_piece_buffer;
    Borrowed piece_size_buffer(g_buffers.piece_size);
    std::vector<int>& piece_size = *piece_size_buffer;
    Borrowed piece_key_buffer(g_buffers.piece_key);
    std::vector<int>& piece_key = *piece_key_buffer;
    findPieces(h, runs, row_begin, run_piece, piece_size, piece_key);

    const int pieces = static_cast<int>(piece_size.size());
    Borrowed small_buffer(g_buffers.small);
    std::vector<std::uint8_t>& small = *small_buffer;
    const bool any_small = markSmallPieces(clusters, piece_size, piece_key, small);

    Borrowed merged_buffer(g_buffers.merged);
    std::vector<int>& merged = *merged_buffer;
    merged.resize(pieces);
    std::iota(merged.begin(), merged.end(), 0);
    if (any_small) mergeSmallPieces(h, runs, row_begin, run_piece, small, merged);
    writePieceIds(w, h, runs, row_begin, run_piece, merged, out);
  }

  // enforceConnectivity's steps. The runs of row y are runs[row_begin[y] ..
  // row_begin[y + 1]).

  // The horizontal runs of equal key, row by row; unusable pixels (key -1)
  // are in none.
  static void findKeyRuns(int w, int h, const std::vector<int>& key, std::vector<Run>& runs,
                          std::vector<int>& row_begin) {
    runs.clear();
    row_begin.assign(static_cast<std::size_t>(h) + 1, 0);
    for (int y = 0; y < h; ++y) {
      row_begin[y] = static_cast<int>(runs.size());
      const int* row = key.data() + static_cast<std::size_t>(y) * w;
      for (int x = 0; x < w;) {
        const int k = row[x];
        const int x1 = static_cast<int>(
            detail::intRunEnd(row, static_cast<std::size_t>(x), static_cast<std::size_t>(w)));
        if (k != -1) runs.push_back({x, x1, k});
        x = x1;
      }
    }
    row_begin[h] = static_cast<int>(runs.size());
  }

  // Calls f(upper run, lower run, overlap) for vertically touching runs.
  template <typename F>
  static void forEachVerticalContact(int h, const std::vector<Run>& runs,
                                     const std::vector<int>& row_begin, F&& f) {
    for (int y = 1; y < h; ++y) {
      int a = row_begin[y - 1];
      int b = row_begin[y];
      while (a < row_begin[y] && b < row_begin[y + 1]) {
        const int overlap = std::min(runs[a].x1, runs[b].x1) - std::max(runs[a].x0, runs[b].x0);
        if (overlap > 0) f(a, b, overlap);
        if (runs[a].x1 < runs[b].x1) {
          ++a;
        } else {
          ++b;
        }
      }
    }
  }

  // Pieces: the 4-connected groups of runs of one key (union-find over
  // vertically touching runs), dense ids in the order of their first run
  // (`run_piece` per run), with their sizes in pixels and their keys.
  static void findPieces(int h, const std::vector<Run>& runs, const std::vector<int>& row_begin,
                         std::vector<int>& run_piece, std::vector<int>& piece_size,
                         std::vector<int>& piece_key) {
    const int run_count = static_cast<int>(runs.size());
    Borrowed parent_buffer(g_buffers.parent);
    std::vector<int>& parent = *parent_buffer;
    parent.resize(run_count);
    std::iota(parent.begin(), parent.end(), 0);
    const auto find = [&parent](int p) {
      while (parent[p] != p) {
        parent[p] = parent[parent[p]];
        p = parent[p];
      }
      return p;
    };
    const auto unite = [&](int a, int b) {
      a = find(a);
      b = find(b);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    };
    forEachVerticalContact(h, runs, row_begin, [&](int a, int b, int) {
      if (runs[a].key == runs[b].key) unite(a, b);
    });

    run_piece.resize(run_count);
    piece_size.clear();
    piece_key.clear();
    for (int r = 0; r < run_count; ++r) {
      const int root = find(r);
      if (root == r) {
        run_piece[r] = static_cast<int>(piece_size.size());
        piece_size.push_back(0);
        piece_key.push_back(runs[r].key);
      } else {
        run_piece[r] = run_piece[root];  // roots precede their runs
      }
      piece_size[run_piece[r]] += runs[r].x1 - runs[r].x0;
    }
  }

  // small[p]: piece p is below oversegmentation.min_segment_points or a quarter of
  // its cluster's nominal area, or no cluster reached it. Returns whether
  // any piece is small.
  bool markSmallPieces(const std::vector<Cluster>& clusters, const std::vector<int>& piece_size,
                       const std::vector<int>& piece_key, std::vector<std::uint8_t>& small) const {
    const int pieces = static_cast<int>(piece_size.size());
    small.assign(pieces, 0);
    bool any_small = false;
    for (int p = 0; p < pieces; ++p) {
      const float nominal = piece_key[p] >= 0 ? clusters[piece_key[p]].nominal_area_px : 0.0f;
      const float threshold =
          std::max(static_cast<float>(config_.min_segment_points), 0.25f * nominal);
      small[p] = piece_size[p] < threshold || piece_key[p] == kUnassigned;
      any_small = any_small || small[p];
    }
    return any_small;
  }

  // merged[p] (every piece its own on entry): the piece that small piece p
  // joins, the neighbour it shares the longest border with, followed
  // through chains.
  static void mergeSmallPieces(int h, const std::vector<Run>& runs,
                               const std::vector<int>& row_begin, const std::vector<int>& run_piece,
                               const std::vector<std::uint8_t>& small, std::vector<int>& merged) {
    const int pieces = static_cast<int>(small.size());
    // Border lengths between a small piece and its neighbours.
    Borrowed contacts_buffer(g_buffers.contacts);
    std::vector<Contact>& contacts = *contacts_buffer;
    contacts.clear();
    const auto touch = [&](int pa, int pb, int length) {
      if (pa == pb) return;
      if (small[pa])
        contacts.push_back(
            {(static_cast<std::uint64_t>(pa) << 32) | static_cast<std::uint32_t>(pb), length});
      if (small[pb])
        contacts.push_back(
            {(static_cast<std::uint64_t>(pb) << 32) | static_cast<std::uint32_t>(pa), length});
    };
    for (int y = 0; y < h; ++y) {
      for (int r = row_begin[y]; r + 1 < row_begin[y + 1]; ++r) {
        if (runs[r].x1 == runs[r + 1].x0) touch(run_piece[r], run_piece[r + 1], 1);
      }
    }
    forEachVerticalContact(h, runs, row_begin, [&](int a, int b, int overlap) {
      touch(run_piece[a], run_piece[b], overlap);
    });
    std::sort(contacts.begin(), contacts.end(),
              [](const Contact& a, const Contact& b) { return a.pair < b.pair; });
    Borrowed target_buffer(g_buffers.target);
    std::vector<int>& target = *target_buffer;  // neighbour with the longest border
    target.assign(pieces, -1);
    Borrowed target_len_buffer(g_buffers.target_len);
    std::vector<int>& target_len = *target_len_buffer;
    target_len.assign(pieces, 0);
    for (std::size_t i = 0; i < contacts.size();) {
      int length = 0;
      std::size_t j = i;
      for (; j < contacts.size() && contacts[j].pair == contacts[i].pair; ++j)
        length += contacts[j].length;
      const int a = static_cast<int>(contacts[i].pair >> 32);
      if (length > target_len[a]) {
        target_len[a] = length;
        target[a] = static_cast<int>(contacts[i].pair & 0xffffffffu);
      }
      i = j;
    }
    // Union-find resolves chains (a small piece into a small piece into a
    // big one) and pairs of small pieces that chose each other.
    const auto find_merged = [&merged](int p) {
      while (merged[p] != p) {
        merged[p] = merged[merged[p]];
        p = merged[p];
      }
      return p;
    };
    for (int p = 0; p < pieces; ++p) {
      if (!small[p] || target[p] < 0) continue;
      const int a = find_merged(p);
      const int b = find_merged(target[p]);
      if (a != b) merged[a] = b;
    }
    for (int p = 0; p < pieces; ++p) merged[p] = find_merged(p);
  }

  // Each pixel once: the runs their pieces' merged ids, the gaps between
  // them -1.
  static void writePieceIds(int w, int h, const std::vector<Run>& runs,
                            const std::vector<int>& row_begin, const std::vector<int>& run_piece,
                            const std::vector<int>& merged, std::vector<int>& out) {
    for (int y = 0; y < h; ++y) {
      int* row = out.data() + static_cast<std::size_t>(y) * w;
      int x = 0;
      for (int r = row_begin[y]; r < row_begin[y + 1]; ++r) {
        std::fill(row + x, row + runs[r].x0, -1);
        std::fill(row + runs[r].x0, row + runs[r].x1, merged[run_piece[r]]);
        x = runs[r].x1;
      }
      std::fill(row + x, row + w, -1);
    }
  }

  // Whether the AVX2 variants (window search, refinement, centre sums, seed
  // density) run: the CPU has AVX2 and the tests did not switch them off.
  bool useAvx2() const {
#if defined(FINDMUG_AVX2_DISPATCH)
    return simd_ == detail::OversegSimd::Auto && detail::cpuHasAvx2();
#else
    return false;
#endif
  }

  OversegmentationConfig config_;
  detail::OversegSimd simd_ = detail::OversegSimd::Auto;
  Weights weights_{};
};

}  // namespace

namespace detail {
void labFromRgb(const Rgb8* colors, const int* pixel, std::size_t count, float* l, float* a,
                float* b, LabSimd simd) {
  labConverter().convertBatch(colors, pixel, count, l, a, b, simd);
}

std::unique_ptr<Oversegmenter> makeOrganizedOversegmenter(const OversegmentationConfig& config,
                                                          OversegSimd simd) {
  return std::make_unique<OrganizedOversegmenter>(config, simd);
}
}  // namespace detail

}  // namespace findmug
