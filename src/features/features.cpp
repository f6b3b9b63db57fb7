// features.cpp — the 14-D patch descriptor (see features.hpp for the layout).
//
// Both entry points feed the same per-patch accumulator and share one
// finaliser, so a segment's features from computeFeatures are exactly those
// computePatchFeatures gives for the same points.
//
// Definitions, all in the ground-aligned frame (z up):
//  - Shape: eigenvalues λ0 <= λ1 <= λ2 of the covariance (scatter / n) of the
//    points, divided by λ0+λ1+λ2. A single point or coincident points have
//    no shape; they are reported as isotropic (1/3, 0, 0).
//  - Normal angle θ(n) = angle between a normal n and the ground normal +z,
//    in [0, π]: 0 for an up-facing horizontal surface (floor, table top),
//    π/2 for a vertical one (wall), π for a down-facing one (ceiling; our
//    normals face the camera). Feature 6 is θ of the mean of the unit
//    normals, feature 7 the circular standard deviation sqrt(-2 ln R) of the
//    per-point θ, R the length of the mean of the unit phasors e^{iθ}.
//    Patches without a single normal use the smallest principal axis of the
//    points (sign unknown, so θ in [0, π/2]) and a spread of 0.
//  - Colour: CIELAB (D65) mean and population standard deviation.
#include "findmug/features/features.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <string>

#include "common/cpu_features.hpp"
#include "features/features_internal.hpp"
#include "findmug/common/error.hpp"
#include "common/scratch.hpp"
#include "common/simd_table.hpp"
#include "common/simd_vec3.hpp"

namespace findmug {

namespace {

// ---- colour ----------------------------------------------------------------

// sRGB D65 linear RGB -> XYZ (IEC 61966-2-1), white point D65 (Y = 1).
constexpr double kM[3][3] = {{0.4124564, 0.3575761, 0.1804375},
                             {0.2126729, 0.7151522, 0.0721750},
                             {0.0193339, 0.1191920, 0.9503041}};
constexpr double kWhite[3] = {0.95047, 1.0, 1.08883};
constexpr double kEpsilon = 216.0 / 24389.0;  // (6/29)^3
constexpr double kKappa = 24389.0 / 27.0;     // (29/3)^3

double srgbToLinear(std::uint8_t c) {
  const double v = c / 255.0;
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

double labF(double t) { return t > kEpsilon ? std::cbrt(t) : (kKappa * t + 16.0) / 116.0; }

// Per-pixel colour conversion for computeFeatures: a 256-entry sRGB
// linearisation table and a linearly interpolated table of the CIELAB f(t)
// (cube root) on [0, 1]. The interpolation error is below 1e-5 in f, i.e.
// about 1e-3 in L*, far below 8-bit quantisation, and it avoids three cube
// roots per pixel (which alone would eat the frame budget).
class FastLab {
 public:
  FastLab() {
    for (int c = 0; c < 256; ++c) linear_[c] = static_cast<float>(srgbToLinear(c));
    for (int k = 0; k <= kSteps; ++k) f_[k] = static_cast<float>(labF(double(k) / kSteps));
    detail::fillInterpolationSteps(f_.data(), kSteps, f_step_.data());
    // The matrix rows pre-divided by the white point, in float.
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col)
        m_[row][col] = static_cast<float>(kM[row][col] / kWhite[row]);
  }
  Eigen::Vector3f operator()(const Rgb8& rgb) const {
    const float r = linear_[rgb.r], g = linear_[rgb.g], b = linear_[rgb.b];
    const float fx = f(m_[0][0] * r + m_[0][1] * g + m_[0][2] * b);
    const float fy = f(m_[1][0] * r + m_[1][1] * g + m_[1][2] * b);
    const float fz = f(m_[2][0] * r + m_[2][1] * g + m_[2][2] * b);
    return {116.0f * fy - 16.0f, 500.0f * (fx - fy), 200.0f * (fy - fz)};
  }

#ifdef FINDMUG_AVX2_DISPATCH
  // operator() of rgb[0..7], as L, a, b lanes: the same float operations in
  // the same order (no FMA), table entries gathered, and f's rare t >= 1
  // lanes (near-white) redone one by one with the double cube root.
  __attribute__((target("avx2"))) void convert8(const Rgb8* rgb, __m256& l, __m256& a,
                                                __m256& b) const {
    const float* lin = linear_.data();
    const __m256 r = _mm256_setr_ps(lin[rgb[0].r], lin[rgb[1].r], lin[rgb[2].r], lin[rgb[3].r],
                                    lin[rgb[4].r], lin[rgb[5].r], lin[rgb[6].r], lin[rgb[7].r]);
    const __m256 g = _mm256_setr_ps(lin[rgb[0].g], lin[rgb[1].g], lin[rgb[2].g], lin[rgb[3].g],
                                    lin[rgb[4].g], lin[rgb[5].g], lin[rgb[6].g], lin[rgb[7].g]);
    const __m256 bl = _mm256_setr_ps(lin[rgb[0].b], lin[rgb[1].b], lin[rgb[2].b], lin[rgb[3].b],
                                     lin[rgb[4].b], lin[rgb[5].b], lin[rgb[6].b], lin[rgb[7].b]);
    __m256 f_of[3];
    for (int row = 0; row < 3; ++row) {
      const __m256 t = _mm256_add_ps(
          _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(m_[row][0]), r),
                        _mm256_mul_ps(_mm256_set1_ps(m_[row][1]), g)),
          _mm256_mul_ps(_mm256_set1_ps(m_[row][2]), bl));
      f_of[row] = f8(t);
    }
    l = _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(116.0f), f_of[1]), _mm256_set1_ps(16.0f));
    a = _mm256_mul_ps(_mm256_set1_ps(500.0f), _mm256_sub_ps(f_of[0], f_of[1]));
    b = _mm256_mul_ps(_mm256_set1_ps(200.0f), _mm256_sub_ps(f_of[1], f_of[2]));
  }
#endif

 private:
  static constexpr int kSteps = 4096;
  float f(float t) const {
    if (t >= 1.0f) return static_cast<float>(labF(t));  // only at (near-)white
    if (t <= 0.0f) return f_[0];
    const float x = t * kSteps;
    const int k = static_cast<int>(x);
    const float w = x - static_cast<float>(k);
    return f_[k] + w * (f_[k + 1] - f_[k]);
  }
#ifdef FINDMUG_AVX2_DISPATCH
  // f on eight lanes.
  __attribute__((target("avx2"))) __m256 f8(__m256 t) const {
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    const __m256 high = _mm256_cmp_ps(t, one, _CMP_GE_OQ);  // t >= 1: below, one by one
    const __m256 low = _mm256_cmp_ps(t, zero, _CMP_LE_OQ);  // t <= 0: f_[0]
    // Lanes outside (0, 1) interpolate at t = 0 (in the table), then are replaced.
    const __m256 x =
        _mm256_blendv_ps(_mm256_mul_ps(t, _mm256_set1_ps(static_cast<float>(kSteps))), zero,
                         _mm256_or_ps(high, low));
    const __m256i k = _mm256_cvttps_epi32(x);
    const __m256 w = _mm256_sub_ps(x, _mm256_cvtepi32_ps(k));
    __m256 v = detail::interpolate8(f_step_.data(), k, w);
    v = _mm256_blendv_ps(v, _mm256_set1_ps(f_[0]), low);
    if (const int high_lanes = _mm256_movemask_ps(high)) {
      alignas(32) float lanes[8], ts[8];
      _mm256_store_ps(lanes, v);
      _mm256_store_ps(ts, t);
      for (int j = 0; j < 8; ++j) {
        if (high_lanes & (1 << j)) lanes[j] = static_cast<float>(labF(ts[j]));
      }
      v = _mm256_load_ps(lanes);
    }
    return v;
  }
#endif
  std::array<float, 256> linear_{};
  std::array<float, kSteps + 1> f_{};
  // (f_[k], f_[k + 1] - f_[k]) for k < kSteps, for f8 (simd_table.hpp).
  alignas(8) std::array<float, 2 * kSteps> f_step_{};
  float m_[3][3] = {};
};

const FastLab& fastLab() {
  static const FastLab table;
  return table;
}

// ---- per-patch accumulation ------------------------------------------------

struct PatchAccumulator {
  int count = 0;
  // Moments of (p - ref): ref is the first point, which keeps the raw-moment
  // covariance well conditioned for patches far from the origin.
  Eigen::Vector3f ref = Eigen::Vector3f::Zero();
  double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
  float z_min = std::numeric_limits<float>::infinity();
  float z_max = -std::numeric_limits<float>::infinity();
  int normal_count = 0;
  double nx = 0, ny = 0, nz = 0;    // sum of unit normals
  double cos_sum = 0, sin_sum = 0;  // sum of e^{iθ}
  double l = 0, a = 0, b = 0, ll = 0, aa = 0, bb = 0;

  bool ref_fixed = false;  // ref given from outside (a run of a known segment)

  void addPoint(const Eigen::Vector3f& p) {
    if (count == 0 && !ref_fixed) ref = p;
    ++count;
    const double x = p.x() - ref.x(), y = p.y() - ref.y(), z = p.z() - ref.z();
    sx += x, sy += y, sz += z;
    sxx += x * x, sxy += x * y, sxz += x * z, syy += y * y, syz += y * z, szz += z * z;
    z_min = std::min(z_min, p.z());
    z_max = std::max(z_max, p.z());
  }
  void addNormal(const Eigen::Vector3f& n) {
    float ux, uy, uz, sin_theta;
    if (!unitNormal(n, ux, uy, uz, sin_theta)) return;
    ++normal_count;
    nx += ux, ny += uy, nz += uz;
    cos_sum += uz;
    sin_sum += sin_theta;
  }
  // The unit normal of `n` and sin θ (θ = angle to +z: cos θ = uz, sin θ =
  // |horizontal part| >= 0); false for a zero or non-finite normal.
  static bool unitNormal(const Eigen::Vector3f& n, float& ux, float& uy, float& uz,
                         float& sin_theta) {
    const float len2 = n.squaredNorm();
    if (!(len2 > 0.0f) || !std::isfinite(len2)) return false;
    const float inv = 1.0f / std::sqrt(len2);
    ux = n.x() * inv, uy = n.y() * inv, uz = n.z() * inv;
    sin_theta = std::sqrt(ux * ux + uy * uy);
    return true;
  }
  void addLab(const Eigen::Vector3f& lab) {
    l += lab.x(), a += lab.y(), b += lab.z();
    ll += double(lab.x()) * lab.x(), aa += double(lab.y()) * lab.y(),
        bb += double(lab.z()) * lab.z();
  }

  // Adds a run summed about the same reference point.
  void merge(const PatchAccumulator& o) {
    if (count == 0) ref = o.ref;
    count += o.count;
    sx += o.sx, sy += o.sy, sz += o.sz;
    sxx += o.sxx, sxy += o.sxy, sxz += o.sxz, syy += o.syy, syz += o.syz, szz += o.szz;
    z_min = std::min(z_min, o.z_min);
    z_max = std::max(z_max, o.z_max);
    normal_count += o.normal_count;
    nx += o.nx, ny += o.ny, nz += o.nz;
    cos_sum += o.cos_sum, sin_sum += o.sin_sum;
    l += o.l, a += o.a, b += o.b, ll += o.ll, aa += o.aa, bb += o.bb;
  }

  FeatureVector finish(Eigen::Vector3f* centroid, SegmentMoments* moments = nullptr) const {
    FeatureVector f{};
    const double n = count;
    const Eigen::Vector3d mean_rel(sx / n, sy / n, sz / n);
    Eigen::Matrix3d cov;
    cov(0, 0) = sxx / n - mean_rel.x() * mean_rel.x();
    cov(1, 1) = syy / n - mean_rel.y() * mean_rel.y();
    cov(2, 2) = szz / n - mean_rel.z() * mean_rel.z();
    cov(0, 1) = cov(1, 0) = sxy / n - mean_rel.x() * mean_rel.y();
    cov(0, 2) = cov(2, 0) = sxz / n - mean_rel.x() * mean_rel.z();
    cov(1, 2) = cov(2, 1) = syz / n - mean_rel.y() * mean_rel.z();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);  // eigenvalues ascending
    const double l0 = std::max(0.0, eig.eigenvalues()(0));
    const double l1 = std::max(l0, eig.eigenvalues()(1));
    const double l2 = std::max(l1, eig.eigenvalues()(2));
    const double sum = l0 + l1 + l2;
    // Relative to the patch's own scale: below ~1e-12 of the coordinates'
    // magnitude the "spread" is rounding noise.
    if (sum > 1e-12) {
      f[0] = static_cast<float>(l0 / sum);
      f[1] = static_cast<float>((l1 - l0) / sum);
      f[2] = static_cast<float>((l2 - l1) / sum);
    } else {
      f[0] = 1.0f / 3.0f;
      f[1] = 0.0f;
      f[2] = 0.0f;
    }

    const Eigen::Vector3d mean = ref.cast<double>() + mean_rel;
    if (centroid) *centroid = mean.cast<float>();
    if (moments) {
      moments->count = n;
      moments->mean = mean;
      moments->scatter = cov * n;
      moments->normal_sum = Eigen::Vector3d(nx, ny, nz);
      moments->max_z = z_max;
    }
    f[3] = static_cast<float>(mean.z());
    f[4] = z_min;
    f[5] = z_max;

    if (normal_count > 0) {
      f[6] = static_cast<float>(std::atan2(std::hypot(nx, ny), nz));
      const double r = std::hypot(cos_sum, sin_sum) / normal_count;
      f[7] = static_cast<float>(std::sqrt(-2.0 * std::log(std::clamp(r, 1e-12, 1.0))));
    } else {
      const Eigen::Vector3d axis = eig.eigenvectors().col(0);
      f[6] = static_cast<float>(std::acos(std::min(1.0, std::abs(axis.z()) / axis.norm())));
      f[7] = 0.0f;
    }

    const double ml = l / n, ma = a / n, mb = b / n;
    f[8] = static_cast<float>(ml);
    f[9] = static_cast<float>(ma);
    f[10] = static_cast<float>(mb);
    f[11] = static_cast<float>(std::sqrt(std::max(0.0, ll / n - ml * ml)));
    f[12] = static_cast<float>(std::sqrt(std::max(0.0, aa / n - ma * ma)));
    f[13] = static_cast<float>(std::sqrt(std::max(0.0, bb / n - mb * mb)));
    return f;
  }
};

// The pixels of one run of computeFeaturesInto (see there), from pixel `i`
// on, summed into `run` (fresh, with its reference point set); returns the
// first pixel after the run. The portable loop.
std::size_t accumulateRun(const int* pixel_segment, const Eigen::Vector3f* points,
                          const Eigen::Vector3f* normals, const Rgb8* colors, std::size_t i,
                          std::size_t pixels, int s, const FastLab& lab, PatchAccumulator& run) {
  // Summed in a local whose address never escapes (no lambda captures it, no
  // pointer leaves), so the compiler keeps what sums it can in registers;
  // captured by a lambda, its 24 sums stayed in memory with a load and a
  // store each per pixel, which made this pass store-bound.
  PatchAccumulator local = run;
  for (; i < pixels; ++i) {
    const int t = pixel_segment[i];
    if (t < 0) continue;
    const Eigen::Vector3f& p = points[i];
    if (!std::isfinite(p.z())) continue;
    if (t != s) break;
    local.addPoint(p);
    local.addNormal(normals[i]);
    local.addLab(lab(colors[i]));
  }
  run = local;
  return i;
}

#ifdef FINDMUG_AVX2_DISPATCH
// The AVX2 feature pass (accumulateImageAvx2) takes the image kFeatureBlock
// pixels at a time: each block's unit normals and CIELAB colours are
// computed eight pixels at a time first (FeatureBlock::prepare), and the
// runs then read them.
constexpr std::size_t kFeatureBlock = 256;

struct alignas(32) FeatureBlock {
  // Per pixel (ux, uy, uz, uz) of the unit normal, or zeros where the normal
  // is zero or not finite; (L, a, b, 0).
  float normal[4 * kFeatureBlock];
  float lab[4 * kFeatureBlock];
  float sin_theta[kFeatureBlock];  // 0 where the normal is not valid
  int normal_valid[kFeatureBlock];
  std::size_t begin = 0, end = 0;  // the pixels held: [begin, end)

  // Pixels [first, first + count), as PatchAccumulator::unitNormal and
  // FastLab's operator() do them one by one (same operations, same order;
  // the tail of fewer than eight by those very functions).
  __attribute__((target("avx2"))) void prepare(const Eigen::Vector3f* normals, const Rgb8* colors,
                                               std::size_t first, std::size_t count,
                                               const FastLab& lab_table);
};

// Eight lanes each of x, y, z, w -> eight (x, y, z, w) quads at out[0..31].
__attribute__((target("avx2"))) inline void storeQuads(float* out, __m256 x, __m256 y, __m256 z,
                                                      __m256 w) {
  const __m256 xy_lo = _mm256_unpacklo_ps(x, y), xy_hi = _mm256_unpackhi_ps(x, y);
  const __m256 zw_lo = _mm256_unpacklo_ps(z, w), zw_hi = _mm256_unpackhi_ps(z, w);
  const __m256 q04 = _mm256_shuffle_ps(xy_lo, zw_lo, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 q15 = _mm256_shuffle_ps(xy_lo, zw_lo, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 q26 = _mm256_shuffle_ps(xy_hi, zw_hi, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 q37 = _mm256_shuffle_ps(xy_hi, zw_hi, _MM_SHUFFLE(3, 2, 3, 2));
  _mm256_store_ps(out, _mm256_permute2f128_ps(q04, q15, 0x20));
  _mm256_store_ps(out + 8, _mm256_permute2f128_ps(q26, q37, 0x20));
  _mm256_store_ps(out + 16, _mm256_permute2f128_ps(q04, q15, 0x31));
  _mm256_store_ps(out + 24, _mm256_permute2f128_ps(q26, q37, 0x31));
}

__attribute__((target("avx2"))) void FeatureBlock::prepare(const Eigen::Vector3f* normals,
                                                           const Rgb8* colors, std::size_t first,
                                                           std::size_t count,
                                                           const FastLab& lab_table) {
  begin = first;
  end = first + count;
  std::size_t j = 0;
  const __m256 zero = _mm256_setzero_ps();
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  for (; j + 8 <= count; j += 8) {
    __m256 nx, ny, nz;
    detail::loadVec3x8(normals[first + j].data(), nx, ny, nz);
    // Eigen's squaredNorm, x x + (y y + z z); valid when > 0 and finite.
    const __m256 len2 = detail::dot3x8(nx, ny, nz, nx, ny, nz);
    const __m256 valid =
        _mm256_and_ps(_mm256_cmp_ps(len2, zero, _CMP_GT_OQ), _mm256_cmp_ps(len2, inf, _CMP_LT_OQ));
    const __m256 inv = _mm256_div_ps(_mm256_set1_ps(1.0f), _mm256_sqrt_ps(len2));
    const __m256 ux = _mm256_and_ps(_mm256_mul_ps(nx, inv), valid);
    const __m256 uy = _mm256_and_ps(_mm256_mul_ps(ny, inv), valid);
    const __m256 uz = _mm256_and_ps(_mm256_mul_ps(nz, inv), valid);
    const __m256 sin_lanes =
        _mm256_sqrt_ps(_mm256_add_ps(_mm256_mul_ps(ux, ux), _mm256_mul_ps(uy, uy)));
    storeQuads(normal + 4 * j, ux, uy, uz, uz);
    _mm256_store_ps(sin_theta + j, sin_lanes);
    _mm256_store_si256(reinterpret_cast<__m256i*>(normal_valid + j),
                       _mm256_srli_epi32(_mm256_castps_si256(valid), 31));
    __m256 l, a, b;
    lab_table.convert8(colors + first + j, l, a, b);
    storeQuads(lab + 4 * j, l, a, b, zero);
  }
  for (; j < count; ++j) {
    float ux = 0.0f, uy = 0.0f, uz = 0.0f, s = 0.0f;
    const bool valid = PatchAccumulator::unitNormal(normals[first + j], ux, uy, uz, s);
    if (!valid) ux = uy = uz = s = 0.0f;
    const float quad[4] = {ux, uy, uz, uz};
    std::copy(quad, quad + 4, normal + 4 * j);
    sin_theta[j] = s;
    normal_valid[j] = valid ? 1 : 0;
    const Eigen::Vector3f c = lab_table(colors[first + j]);
    const float lab_quad[4] = {c.x(), c.y(), c.z(), 0.0f};
    std::copy(lab_quad, lab_quad + 4, lab + 4 * j);
  }
}

// The pass of computeFeaturesInto (see there) over the whole image, each
// run's double sums four to an AVX2 register: (sx, sy, sz, -),
// (sxx, sxy, sxz, syy), (syz, szz, -, -), (nx, ny, nz, cos_sum),
// (l, a, b, -), (ll, aa, bb, -). Each lane does the scalar code's operation
// on the same operands in the same order (float differences and colours
// converted to double, then products and sums), so the sums are the same
// bits; pixels without a valid normal and the unused lanes add +0, which
// leaves a sum that started at +0 unchanged. Why: the scalar loop has 24
// running sums for 16 SSE registers and kept some in memory, so each pixel
// waited for the previous one's stores, and it spent as long again on each
// pixel's square roots, division and colour table lookups one at a time.
// It walks the whole image itself, as computeFeaturesInto's portable loop
// does, rather than being called once per run from that loop: the call per
// run made the pass 1.08-1.10 of this (stage_ab, 31 NYU frames).
// Returns the first pixel whose segment is not below `segment_count` (the
// caller reports it), or `pixels`.
__attribute__((target("avx2"))) std::size_t accumulateImageAvx2(
    const int* pixel_segment, const Eigen::Vector3f* points, const Eigen::Vector3f* normals,
    const Rgb8* colors, std::size_t pixels, const FastLab& lab, PatchAccumulator* acc,
    std::size_t segment_count, FeatureBlock& block) {
  block.begin = block.end = 0;
  std::size_t i = 0;
  while (i < pixels) {
    const int s = pixel_segment[i];
    if (s < 0 || !std::isfinite(points[i].z())) {
      ++i;
      continue;
    }
    if (static_cast<std::size_t>(s) >= segment_count) return i;
    PatchAccumulator& target = acc[static_cast<std::size_t>(s)];
    if (target.count == 0) target.ref = points[i];
    const __m128 ref = _mm_setr_ps(target.ref.x(), target.ref.y(), target.ref.z(), 0.0f);
    __m256d first = _mm256_setzero_pd(), second = _mm256_setzero_pd();
    __m256d second_yz = _mm256_setzero_pd(), normal = _mm256_setzero_pd();
    __m256d colour = _mm256_setzero_pd(), colour_sq = _mm256_setzero_pd();
    double sin_sum = 0.0;
    int count = 0, normal_count = 0;
    float z_min = std::numeric_limits<float>::infinity();
    float z_max = -std::numeric_limits<float>::infinity();
    for (; i < pixels; ++i) {
      const int t = pixel_segment[i];
      if (t < 0) continue;
      const Eigen::Vector3f& p = points[i];
      if (!std::isfinite(p.z())) continue;
      if (t != s) break;
      if (i >= block.end) {
        const std::size_t begin = i - i % kFeatureBlock;
        block.prepare(normals, colors, begin, std::min(kFeatureBlock, pixels - begin), lab);
      }
      const std::size_t j = i - block.begin;
      ++count;
      // (x, y, z, 0) = p - ref in float, then in double, as addPoint.
      const __m256d d =
          _mm256_cvtps_pd(_mm_sub_ps(_mm_setr_ps(p.x(), p.y(), p.z(), 0.0f), ref));
      first = _mm256_add_pd(first, d);
      // (x, x, x, y) * (x, y, z, y) and (y, z, z, 0) * (z, z, 0, 0).
      second = _mm256_add_pd(second, _mm256_mul_pd(_mm256_permute4x64_pd(d, 0x40),
                                                   _mm256_permute4x64_pd(d, 0x64)));
      second_yz = _mm256_add_pd(second_yz, _mm256_mul_pd(_mm256_permute4x64_pd(d, 0xE9),
                                                         _mm256_permute4x64_pd(d, 0xFA)));
      z_min = std::min(z_min, p.z());
      z_max = std::max(z_max, p.z());
      normal = _mm256_add_pd(normal, _mm256_cvtps_pd(_mm_load_ps(block.normal + 4 * j)));
      sin_sum += block.sin_theta[j];
      normal_count += block.normal_valid[j];
      const __m256d c = _mm256_cvtps_pd(_mm_load_ps(block.lab + 4 * j));
      colour = _mm256_add_pd(colour, c);
      colour_sq = _mm256_add_pd(colour_sq, _mm256_mul_pd(c, c));
    }
    alignas(32) double lanes[6][4];
    _mm256_store_pd(lanes[0], first);
    _mm256_store_pd(lanes[1], second);
    _mm256_store_pd(lanes[2], second_yz);
    _mm256_store_pd(lanes[3], normal);
    _mm256_store_pd(lanes[4], colour);
    _mm256_store_pd(lanes[5], colour_sq);
    PatchAccumulator run;
    run.ref = target.ref;
    run.count = count;
    run.sx = lanes[0][0], run.sy = lanes[0][1], run.sz = lanes[0][2];
    run.sxx = lanes[1][0], run.sxy = lanes[1][1], run.sxz = lanes[1][2], run.syy = lanes[1][3];
    run.syz = lanes[2][0], run.szz = lanes[2][1];
    run.z_min = z_min, run.z_max = z_max;
    run.normal_count = normal_count;
    run.nx = lanes[3][0], run.ny = lanes[3][1], run.nz = lanes[3][2], run.cos_sum = lanes[3][3];
    run.sin_sum = sin_sum;
    run.l = lanes[4][0], run.a = lanes[4][1], run.b = lanes[4][2];
    run.ll = lanes[5][0], run.aa = lanes[5][1], run.bb = lanes[5][2];
    target.merge(run);
  }
  return pixels;
}
#endif

}  // namespace

Eigen::Vector3f rgbToLab(const Rgb8& rgb) {
  const double r = srgbToLinear(rgb.r), g = srgbToLinear(rgb.g), b = srgbToLinear(rgb.b);
  const double fx = labF((kM[0][0] * r + kM[0][1] * g + kM[0][2] * b) / kWhite[0]);
  const double fy = labF((kM[1][0] * r + kM[1][1] * g + kM[1][2] * b) / kWhite[1]);
  const double fz = labF((kM[2][0] * r + kM[2][1] * g + kM[2][2] * b) / kWhite[2]);
  return Eigen::Vector3d(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)).cast<float>();
}

FeatureVector computePatchFeatures(const std::vector<Eigen::Vector3f>& points_ground,
                                   const std::vector<Eigen::Vector3f>& normals_ground,
                                   const std::vector<Rgb8>& colors) {
  if (normals_ground.size() != points_ground.size() || colors.size() != points_ground.size()) {
    std::ostringstream msg;
    msg << "computePatchFeatures: " << points_ground.size() << " points, " << normals_ground.size()
        << " normals and " << colors.size() << " colours (must be equal)";
    throw Error(msg.str());
  }
  PatchAccumulator acc;
  const FastLab& lab = fastLab();
  for (std::size_t i = 0; i < points_ground.size(); ++i) {
    const Eigen::Vector3f& p = points_ground[i];
    if (!p.allFinite()) continue;
    acc.addPoint(p);
    acc.addNormal(normals_ground[i]);
    acc.addLab(lab(colors[i]));
  }
  if (acc.count == 0) {
    throw Error("computePatchFeatures: patch of " + std::to_string(points_ground.size()) +
                " points has no finite point");
  }
  return acc.finish(nullptr);
}

SegmentFeatures computeFeatures(const OrganizedCloud& cloud_ground,
                                const NormalImage& normals_ground,
                                const Oversegmentation& segmentation) {
  SegmentFeatures out;
  computeFeaturesInto(cloud_ground, normals_ground, segmentation, out);
  return out;
}

void computeFeaturesInto(const OrganizedCloud& cloud_ground, const NormalImage& normals_ground,
                         const Oversegmentation& segmentation, SegmentFeatures& out) {
  detail::computeFeaturesInto(cloud_ground, normals_ground, segmentation, out,
                              detail::FeatureSimd::Auto);
}

void detail::computeFeaturesInto(const OrganizedCloud& cloud_ground,
                                 const NormalImage& normals_ground,
                                 const Oversegmentation& segmentation, SegmentFeatures& out,
                                 FeatureSimd simd) {
  const std::size_t pixels = static_cast<std::size_t>(std::max(segmentation.width, 0)) *
                             static_cast<std::size_t>(std::max(segmentation.height, 0));
  if (cloud_ground.width != segmentation.width || cloud_ground.height != segmentation.height ||
      normals_ground.width != segmentation.width || normals_ground.height != segmentation.height ||
      cloud_ground.points.size() != pixels || cloud_ground.colors.size() != pixels ||
      normals_ground.normals.size() != pixels || segmentation.pixel_segment.size() != pixels) {
    std::ostringstream msg;
    msg << "computeFeatures: grids disagree: segmentation " << segmentation.width << "x"
        << segmentation.height << " (" << segmentation.pixel_segment.size()
        << " pixel labels), cloud " << cloud_ground.width << "x" << cloud_ground.height << " ("
        << cloud_ground.points.size() << " points, " << cloud_ground.colors.size()
        << " colours), normals " << normals_ground.width << "x" << normals_ground.height << " ("
        << normals_ground.normals.size() << ")";
    throw Error(msg.str());
  }
  const std::size_t segment_count = segmentation.segments.size();
  // Working memory kept per thread between frames (scratch.hpp).
  thread_local std::vector<PatchAccumulator> acc_tls;
  detail::Borrowed acc_buffer(acc_tls);
  std::vector<PatchAccumulator>& acc = *acc_buffer;
  acc.assign(segment_count, PatchAccumulator{});
  const FastLab& lab = fastLab();
#ifdef FINDMUG_AVX2_DISPATCH
  const bool avx2 = simd == detail::FeatureSimd::Auto && detail::cpuHasAvx2();
#else
  const bool avx2 = false;
  (void)simd;
#endif

  // One sequential pass over the image. Pixels come in horizontal runs of
  // the same segment (a run goes on across pixels without a valid point or
  // a segment); each run is summed in local variables and merged into its
  // segment's accumulator once (accumulateRun, or accumulateImageAvx2 with
  // the sums in AVX2 registers). The run uses the segment's reference point,
  // so merging is plain addition.
  const int* pixel_segment = segmentation.pixel_segment.data();
  const Eigen::Vector3f* points = cloud_ground.points.data();
  const Eigen::Vector3f* normals = normals_ground.normals.data();
  const Rgb8* colors = cloud_ground.colors.data();
  const auto badSegment = [&](std::size_t pixel) {
    return Error("computeFeatures: pixel " + std::to_string(pixel) + " belongs to segment " +
                 std::to_string(pixel_segment[pixel]) + " but there are only " +
                 std::to_string(segment_count));
  };
#ifdef FINDMUG_AVX2_DISPATCH
  if (avx2) {
    // On the heap (10 KB, once per thread): static TLS space is small.
    thread_local std::unique_ptr<FeatureBlock> block;
    if (!block) block = std::make_unique<FeatureBlock>();
    const std::size_t bad = accumulateImageAvx2(pixel_segment, points, normals, colors, pixels,
                                                lab, acc.data(), segment_count, *block);
    if (bad < pixels) throw badSegment(bad);
  }
#endif
  std::size_t i = avx2 ? pixels : 0;
  while (i < pixels) {
    const int s = pixel_segment[i];
    if (s < 0 || !std::isfinite(points[i].z())) {
      ++i;
      continue;
    }
    if (static_cast<std::size_t>(s) >= segment_count) throw badSegment(i);
    PatchAccumulator& target = acc[static_cast<std::size_t>(s)];
    if (target.count == 0) target.ref = points[i];
    PatchAccumulator run;
    run.ref = target.ref;
    run.ref_fixed = true;
    i = accumulateRun(pixel_segment, points, normals, colors, i, pixels, s, lab, run);
    target.merge(run);
  }

  out.features.resize(segment_count);
  out.centroids.resize(segment_count);
  out.moments.resize(segment_count);
  out.regions.clear();
  out.scene.clear();
  out.objects.clear();
  for (std::size_t s = 0; s < segment_count; ++s) {
    if (acc[s].count == 0) {
      throw Error("computeFeatures: segment " + std::to_string(s) + " (" +
                  std::to_string(segmentation.segments[s].size()) + " pixels) has no valid point");
    }
    out.features[s] = acc[s].finish(&out.centroids[s], &out.moments[s]);
  }
}

}  // namespace findmug
