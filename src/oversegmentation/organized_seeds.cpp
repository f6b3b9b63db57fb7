// organized_seeds.cpp — the organized oversegmenter's seeds (step 2 of
// oversegmentation_organized.cpp): where the surface needs them, at a
// density that follows depth and slant, off colour and depth edges.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "common/cpu_features.hpp"
#include "common/scratch.hpp"
#include "oversegmentation/organized_internal.hpp"

namespace findmug::detail::organized {
namespace {

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

struct SeedRect {  // a cell of the adaptive seed grid, coarse pixels
  int x0, y0, x1, y1;
};

// placeSeeds' working memory, kept per thread between frames (scratch.hpp).
struct SeedBuffers {
  std::vector<double> density, row_terms;
  std::vector<int> valid;
  std::vector<SeedRect> stack;
};
thread_local SeedBuffers g_seed_buffers;

using detail::Borrowed;

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
  const __m256i valid_bytes =
      _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(block_valid + first)));
  for (int half = 0; half < 2; ++half) {
    const __m128 pz4 = half == 0 ? _mm256_castps256_ps128(pz) : _mm256_extractf128_ps(pz, 1);
    const __m128 cos4 =
        half == 0 ? _mm256_castps256_ps128(cosine) : _mm256_extractf128_ps(cosine, 1);
    const __m128i valid4 =
        half == 0 ? _mm256_castsi256_si128(valid_bytes) : _mm256_extracti128_si256(valid_bytes, 1);
    const __m256d pzd = _mm256_cvtps_pd(pz4);
    // std::min(f, k) = k < f ? k : f: min_pd(k, f) = k < f ? k : f.
    const __m256d footprint =
        _mm256_min_pd(_mm256_set1_pd(kMaxFootprint),
                      _mm256_div_pd(_mm256_mul_pd(pzd, pzd), _mm256_cvtps_pd(cos4)));
    const __m256d count = _mm256_cvtepi32_pd(valid4);
    const __m256d density =
        _mm256_div_pd(_mm256_mul_pd(_mm256_mul_pd(count, footprint), _mm256_set1_pd(pixel_solid)),
                      _mm256_set1_pd(per_seed_area));
    // Pixels without a valid full pixel: 0, as seedDensity.
    const __m256d none = _mm256_castsi256_pd(
        _mm256_cmpeq_epi64(_mm256_cvtepi32_epi64(valid4), _mm256_setzero_si256()));
    _mm256_storeu_pd(out + 4 * half, _mm256_andnot_pd(none, density));
  }
}
#endif

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

// Central-difference feature gradient; infinite next to invalid pixels or
// the image border (no seed on the rim of a hole).
float gradient(const FeatureGrid& g, int x, int y, const Weights& wt) {
  if (x <= 0 || y <= 0 || x + 1 >= g.width || y + 1 >= g.height) {
    return std::numeric_limits<float>::infinity();
  }
  const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
  const std::size_t l = i - 1, r = i + 1, u = i - g.width, d = i + g.width;
  if (!g.valid(l) || !g.valid(r) || !g.valid(u) || !g.valid(d)) {
    return std::numeric_limits<float>::infinity();
  }
  return featureDistance(g, l, r, wt) + featureDistance(g, u, d, wt);
}

// The valid pixel nearest the cell centre, moved to the lowest-gradient
// pixel of its 3x3 neighbourhood so that seeds avoid edges.
std::size_t seedPixel(const FeatureGrid& g, int x0, int y0, int x1, int y1, const Weights& wt) {
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
  float chosen_gradient = gradient(g, nx, ny, wt);
  for (int y = std::max(0, ny - 1); y <= std::min(g.height - 1, ny + 1); ++y) {
    for (int x = std::max(0, nx - 1); x <= std::min(g.width - 1, nx + 1); ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
      if (!g.valid(i)) continue;
      const float grad = gradient(g, x, y, wt);
      if (grad < chosen_gradient) {
        chosen_gradient = grad;
        chosen = i;
      }
    }
  }
  return chosen;
}

}  // namespace

void placeSeeds(const OrganizedCloud& cloud, const FeatureGrid& coarse,
                const std::vector<std::uint8_t>& block_valid, const OversegmentationConfig& config,
                const Weights& weights, bool avx2, std::vector<Cluster>& clusters) {
  clusters.clear();
  double fx = estimateFocal(cloud, true);
  double fy = estimateFocal(cloud, false);
  if (std::isnan(fx)) fx = fy;  // square pixels when one axis cannot tell
  if (std::isnan(fy)) fy = fx;
  if (std::isnan(fx)) return;  // valid points in a single pixel: no segment

  // Seeds per full-resolution pixel = surface area / area per seed.
  const int cw = coarse.width;
  const int chh = coarse.height;
  const double per_seed_area = static_cast<double>(config.seed_resolution_m) *
                               config.seed_resolution_m / config.organized_seed_density;
  const double pixel_solid = 1.0 / (fx * fy);
  // Integral images (cw+1)x(chh+1) of seed density and of valid pixels.
  Borrowed density_buffer(g_seed_buffers.density);
  std::vector<double>& density = *density_buffer;
  density.assign((cw + 1) * static_cast<std::size_t>(chh + 1), 0.0);
  Borrowed valid_buffer(g_seed_buffers.valid);
  std::vector<int>& valid = *valid_buffer;
  valid.assign((cw + 1) * static_cast<std::size_t>(chh + 1), 0);
  const auto at = [cw](int x, int y) { return static_cast<std::size_t>(y) * (cw + 1) + x; };
  // Each row's densities first (eight at a time with AVX2), then its
  // running sums in order. A pixel without a valid full pixel adds +0,
  // which leaves the sum (never -0) as it is.
  Borrowed row_terms_buffer(g_seed_buffers.row_terms);
  std::vector<double>& row_terms = *row_terms_buffer;
  row_terms.resize(static_cast<std::size_t>(cw));
#if !defined(FINDMUG_AVX2_DISPATCH)
  (void)avx2;
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
  const int min_valid = std::max(1, config.min_segment_points / (kCoarseStride * kCoarseStride));
  const float half_factor = 0.5f * static_cast<float>(config.search_window_factor);
  Borrowed stack_buffer(g_seed_buffers.stack);
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
    const std::size_t seed = seedPixel(coarse, r.x0, r.y0, r.x1, r.y1, weights);
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

}  // namespace findmug::detail::organized
