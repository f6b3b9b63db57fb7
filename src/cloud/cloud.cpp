// cloud.cpp — depth back-projection, organized-grid normals, rigid transforms.
//
// Normals: a pixel's normal is the cross product of a horizontal and a
// vertical tangent, each the difference between the points `window_radius_px`
// pixels to either side (central difference, or one-sided where a neighbour is
// missing or lies across a depth discontinuity). Those raw normals are then
// box-averaged (`smoothing_radius_px`) over the pixel's own surface (the box
// stops at depth discontinuities) to beat down Kinect depth quantisation,
// which at 3 m is a few centimetres per step and tilts single-difference
// normals by tens of degrees. On NYU floors at 2..4 m the median error against
// the fitted floor plane drops from ~10 to ~6 degrees with the defaults
// (r = 4, smoothing 4: about 17 px of support, like PCL supervoxels' 5 cm
// normal radius at 2..3 m). Everything is O(1) per pixel with separable
// running sums, so a 640x480 frame costs a few milliseconds on one core.
#include "findmug/cloud/cloud.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>

#include "cloud/cloud_internal.hpp"
#include "common/cpu_features.hpp"
#include "findmug/common/error.hpp"
#include "common/simd_vec3.hpp"

namespace findmug {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
const Eigen::Vector3f kNaNVector(kNaN, kNaN, kNaN);

void checkCloudShape(const OrganizedCloud& cloud, const char* what) {
  const auto pixels = static_cast<std::size_t>(std::max(cloud.width, 0)) *
                      static_cast<std::size_t>(std::max(cloud.height, 0));
  if (cloud.width <= 0 || cloud.height <= 0 || cloud.points.size() != pixels) {
    std::ostringstream msg;
    msg << what << ": organized cloud is " << cloud.width << "x" << cloud.height << " but holds "
        << cloud.points.size() << " points";
    throw Error(msg.str());
  }
  if (!cloud.colors.empty() && cloud.colors.size() != pixels) {
    std::ostringstream msg;
    msg << what << ": organized cloud has " << cloud.colors.size() << " colours for " << pixels
        << " points";
    throw Error(msg.str());
  }
}

// Tangent along one image axis at pixel `c`, from neighbours `a` (before) and
// `b` (after). A neighbour counts when it is valid and its depth is within
// `max_jump` of the centre's. Returns false when no tangent is possible.
inline bool tangent(const Eigen::Vector3f& a, const Eigen::Vector3f& c, const Eigen::Vector3f& b,
                    float max_jump, Eigen::Vector3f& out) {
  const bool a_ok = std::isfinite(a.z()) && std::abs(a.z() - c.z()) <= max_jump;
  const bool b_ok = std::isfinite(b.z()) && std::abs(b.z() - c.z()) <= max_jump;
  if (a_ok && b_ok) {
    out = b - a;
  } else if (b_ok) {
    out = b - c;
  } else if (a_ok) {
    out = c - a;
  } else {
    return false;
  }
  return true;
}

// Raw normal of pixel (u, v) (valid) from differences at +-r pixels,
// oriented towards the camera (the optical centre is the origin, so
// n.dot(p) < 0). False when there is none (no tangent along an axis, or a
// degenerate cross product).
inline bool rawNormal(const Eigen::Vector3f* pts, int w, int h, int r, float max_jump_rel, int u,
                      int v, Eigen::Vector3f& normal) {
  const std::size_t i = static_cast<std::size_t>(v) * w + u;
  const Eigen::Vector3f& c = pts[i];
  // The tolerated depth step grows with depth: both the sensor noise and
  // the depth change across r pixels of an oblique surface do.
  const float max_jump = max_jump_rel * c.z();
  const int u_left = std::max(0, u - r);
  const int u_right = std::min(w - 1, u + r);
  const int v_up = std::max(0, v - r);
  const int v_down = std::min(h - 1, v + r);
  Eigen::Vector3f th, tv;
  if (!tangent(pts[static_cast<std::size_t>(v) * w + u_left], c,
               pts[static_cast<std::size_t>(v) * w + u_right], max_jump, th) ||
      !tangent(pts[static_cast<std::size_t>(v_up) * w + u], c,
               pts[static_cast<std::size_t>(v_down) * w + u], max_jump, tv)) {
    return false;
  }
  normal = th.cross(tv);
  const float norm = normal.norm();
  if (!(norm > 0.0f)) return false;
  normal /= norm;
  if (normal.dot(c) > 0.0f) normal = -normal;
  return true;
}

// Raw normals of pixels [u0, u1) of row v into n (NaN where there is none).
void rawNormalsScalar(const Eigen::Vector3f* pts, int w, int h, int r, float max_jump_rel, int v,
                      int u0, int u1, Eigen::Vector3f* n) {
  for (int u = u0; u < u1; ++u) {
    const std::size_t i = static_cast<std::size_t>(v) * w + u;
    if (!std::isfinite(pts[i].z())) continue;
    Eigen::Vector3f normal;
    if (rawNormal(pts, w, h, r, max_jump_rel, u, v, normal)) n[i] = normal;
  }
}

#if defined(FINDMUG_AVX2_DISPATCH)
// Eight consecutive points (24 floats, x y z interleaved) into one register
// per coordinate, and back. Lanes {0,3,6}, {1,4,7} and {2,5} of the three
// loaded registers hold one coordinate each in a fixed rotation; blends
// gather them and a lane permutation puts them in order. A blend keeps its
// first operand in lanes {0,3,6} and takes lanes {1,4,7} (kLanesB) and
// {2,5} (kLanesC) from the others.
constexpr int kLanesB = 0x92, kLanesC = 0x24;

__attribute__((target("avx2"))) inline void loadPoints8(const Eigen::Vector3f* p, __m256& x,
                                                       __m256& y, __m256& z) {
  const float* f = p->data();
  const __m256 m0 = _mm256_loadu_ps(f), m1 = _mm256_loadu_ps(f + 8), m2 = _mm256_loadu_ps(f + 16);
  const __m256 tx = _mm256_blend_ps(_mm256_blend_ps(m0, m1, kLanesB), m2, kLanesC);
  const __m256 ty = _mm256_blend_ps(_mm256_blend_ps(m2, m0, kLanesB), m1, kLanesC);
  const __m256 tz = _mm256_blend_ps(_mm256_blend_ps(m1, m2, kLanesB), m0, kLanesC);
  x = _mm256_permutevar8x32_ps(tx, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
  y = _mm256_permutevar8x32_ps(ty, _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6));
  z = _mm256_permutevar8x32_ps(tz, _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
}

__attribute__((target("avx2"))) inline void storePoints8(Eigen::Vector3f* p, __m256 x, __m256 y,
                                                        __m256 z) {
  const __m256 tx = _mm256_permutevar8x32_ps(x, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
  const __m256 ty = _mm256_permutevar8x32_ps(y, _mm256_setr_epi32(5, 0, 3, 6, 1, 4, 7, 2));
  const __m256 tz = _mm256_permutevar8x32_ps(z, _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
  float* f = p->data();
  _mm256_storeu_ps(f, _mm256_blend_ps(_mm256_blend_ps(tx, ty, kLanesB), tz, kLanesC));
  _mm256_storeu_ps(f + 8, _mm256_blend_ps(_mm256_blend_ps(tz, tx, kLanesB), ty, kLanesC));
  _mm256_storeu_ps(f + 16, _mm256_blend_ps(_mm256_blend_ps(ty, tz, kLanesB), tx, kLanesC));
}

// tangent() on eight pixels: the tangent's coordinates and whether it exists.
__attribute__((target("avx2"))) inline __m256 tangent8(const Eigen::Vector3f* a,
                                                      const Eigen::Vector3f* b, __m256 cx,
                                                      __m256 cy, __m256 cz, __m256 max_jump,
                                                      __m256& tx, __m256& ty, __m256& tz) {
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  __m256 ax, ay, az, bx, by, bz;
  loadPoints8(a, ax, ay, az);
  loadPoints8(b, bx, by, bz);
  // isfinite(z) && |z - c.z| <= max_jump; every comparison is false on NaN.
  const __m256 a_ok = _mm256_and_ps(
      _mm256_cmp_ps(_mm256_and_ps(az, abs_mask), inf, _CMP_LT_OQ),
      _mm256_cmp_ps(_mm256_and_ps(_mm256_sub_ps(az, cz), abs_mask), max_jump, _CMP_LE_OQ));
  const __m256 b_ok = _mm256_and_ps(
      _mm256_cmp_ps(_mm256_and_ps(bz, abs_mask), inf, _CMP_LT_OQ),
      _mm256_cmp_ps(_mm256_and_ps(_mm256_sub_ps(bz, cz), abs_mask), max_jump, _CMP_LE_OQ));
  // Both: b - a; only b: b - c; only a: c - a.
  const __m256 lo_x = _mm256_blendv_ps(cx, ax, a_ok), lo_y = _mm256_blendv_ps(cy, ay, a_ok),
               lo_z = _mm256_blendv_ps(cz, az, a_ok);
  const __m256 hi_x = _mm256_blendv_ps(cx, bx, b_ok), hi_y = _mm256_blendv_ps(cy, by, b_ok),
               hi_z = _mm256_blendv_ps(cz, bz, b_ok);
  tx = _mm256_sub_ps(hi_x, lo_x);
  ty = _mm256_sub_ps(hi_y, lo_y);
  tz = _mm256_sub_ps(hi_z, lo_z);
  return _mm256_or_ps(a_ok, b_ok);
}

// rawNormalsScalar for a whole image, eight pixels at a time where the
// +-r neighbours of all eight lie inside the row; the rest scalar. The same
// IEEE operations in the same order as rawNormal (Eigen's 3-term sums are
// x + (y + z); no FMA: the target is "avx2", not "fma"), so the normals are
// bit-identical to the scalar code (NormalsAvx2.MatchesTheScalarCodeBitForBit).
__attribute__((target("avx2"))) void rawNormalsAvx2(const Eigen::Vector3f* pts, int w, int h,
                                                   int r, float max_jump_rel,
                                                   Eigen::Vector3f* n) {
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 sign_mask = _mm256_castsi256_ps(_mm256_set1_epi32(static_cast<int>(0x80000000u)));
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 zero = _mm256_setzero_ps();
  const __m256 nan = _mm256_set1_ps(std::numeric_limits<float>::quiet_NaN());
  const __m256 jump_rel = _mm256_set1_ps(max_jump_rel);
  for (int v = 0; v < h; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * w;
    const std::size_t up = static_cast<std::size_t>(std::max(0, v - r)) * w;
    const std::size_t down = static_cast<std::size_t>(std::min(h - 1, v + r)) * w;
    int u = std::min(r, w);
    rawNormalsScalar(pts, w, h, r, max_jump_rel, v, 0, u, n);
    for (; u + 8 + r <= w; u += 8) {
      __m256 cx, cy, cz;
      loadPoints8(pts + row + u, cx, cy, cz);
      const __m256 valid = _mm256_cmp_ps(_mm256_and_ps(cz, abs_mask), inf, _CMP_LT_OQ);
      if (_mm256_movemask_ps(valid) == 0) continue;  // a hole: n keeps its NaN
      const __m256 max_jump = _mm256_mul_ps(jump_rel, cz);
      __m256 hx, hy, hz, vx, vy, vz;
      const __m256 h_ok =
          tangent8(pts + row + u - r, pts + row + u + r, cx, cy, cz, max_jump, hx, hy, hz);
      const __m256 v_ok = tangent8(pts + up + u, pts + down + u, cx, cy, cz, max_jump, vx, vy, vz);
      // th.cross(tv)
      __m256 nx = _mm256_sub_ps(_mm256_mul_ps(hy, vz), _mm256_mul_ps(hz, vy));
      __m256 ny = _mm256_sub_ps(_mm256_mul_ps(hz, vx), _mm256_mul_ps(hx, vz));
      __m256 nz = _mm256_sub_ps(_mm256_mul_ps(hx, vy), _mm256_mul_ps(hy, vx));
      const __m256 norm = _mm256_sqrt_ps(_mm256_add_ps(
          _mm256_mul_ps(nx, nx), _mm256_add_ps(_mm256_mul_ps(ny, ny), _mm256_mul_ps(nz, nz))));
      nx = _mm256_div_ps(nx, norm);
      ny = _mm256_div_ps(ny, norm);
      nz = _mm256_div_ps(nz, norm);
      const __m256 dot = _mm256_add_ps(
          _mm256_mul_ps(nx, cx), _mm256_add_ps(_mm256_mul_ps(ny, cy), _mm256_mul_ps(nz, cz)));
      const __m256 flip = _mm256_and_ps(_mm256_cmp_ps(dot, zero, _CMP_GT_OQ), sign_mask);
      nx = _mm256_xor_ps(nx, flip);
      ny = _mm256_xor_ps(ny, flip);
      nz = _mm256_xor_ps(nz, flip);
      const __m256 ok = _mm256_and_ps(_mm256_and_ps(valid, _mm256_and_ps(h_ok, v_ok)),
                                      _mm256_cmp_ps(norm, zero, _CMP_GT_OQ));
      storePoints8(n + row + u, _mm256_blendv_ps(nan, nx, ok), _mm256_blendv_ps(nan, ny, ok),
                   _mm256_blendv_ps(nan, nz, ok));
    }
    rawNormalsScalar(pts, w, h, r, max_jump_rel, v, u, w, n);
  }
}

// Whether the eight lanes of v hold one value.
__attribute__((target("avx2"))) inline bool sameInEveryLane(__m256i v) {
  const __m256i first = _mm256_permutevar8x32_epi32(v, _mm256_setzero_si256());
  return _mm256_movemask_epi8(_mm256_cmpeq_epi32(v, first)) == -1;
}

// k % ring for prefix rows k >= k0 with k - k0 < ring, given k0 and k0 % ring.
__attribute__((target("avx2"))) inline __m256i ringSlot(__m256i k, __m256i k0, __m256i k0_slot,
                                                       __m256i ring_last, __m256i ring) {
  const __m256i slot = _mm256_add_epi32(_mm256_sub_epi32(k, k0), k0_slot);
  return _mm256_sub_epi32(slot, _mm256_and_si256(_mm256_cmpgt_epi32(slot, ring_last), ring));
}

// The column step of smoothNormals for pixels [u0, u1) of row v: each
// pixel's box sum is the difference of two prefix rows, picked per pixel
// (its vertical run clips the box), so the eight lanes gather their rows,
// unless the eight read the same two rows (plain loads then).
// The same operations as the scalar loop there (Eigen's norm is
// sqrt(x^2 + (y^2 + z^2))), so the same normals to the bit. `prefix` holds
// rows k of the column prefix table at slot k % ring (of width w); slots of
// rows max(0, v - r) .. v + r + 1 are all valid.
__attribute__((target("avx2"))) void smoothColumnsAvx2(
    Eigen::Vector3f* n, const std::int32_t* run_start, const std::int32_t* run_end,
    const Eigen::Vector3f* prefix, int w, int r, int ring, int v, int u0, int u1) {
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 min_norm = _mm256_set1_ps(1e-3f);
  const int k0 = std::max(0, v - r);  // lowest prefix row a pixel of this row reads
  const __m256i first_row = _mm256_set1_epi32(k0);
  const __m256i first_slot = _mm256_set1_epi32(k0 % ring);
  const __m256i ring_size = _mm256_set1_epi32(ring);
  const __m256i ring_last = _mm256_set1_epi32(ring - 1);
  const __m256i row_floats = _mm256_set1_epi32(3 * w);
  const __m256i lane_floats = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
  const __m256i lowest = _mm256_set1_epi32(v - r), highest = _mm256_set1_epi32(v + r);
  const float* table = prefix->data();
  const std::size_t base = static_cast<std::size_t>(v) * w;
  for (int u = u0; u + 8 <= u1; u += 8) {
    const std::size_t i = base + u;
    __m256 x, y, z;
    loadPoints8(n + i, x, y, z);
    const __m256 has_normal = _mm256_cmp_ps(_mm256_and_ps(x, abs_mask), inf, _CMP_LT_OQ);
    if (_mm256_movemask_ps(has_normal) == 0) continue;
    const __m256i lo = _mm256_max_epi32(
        lowest, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(run_start + i)));
    const __m256i hi = _mm256_min_epi32(
        highest, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(run_end + i)));
    const __m256i top_slot = ringSlot(_mm256_add_epi32(hi, _mm256_set1_epi32(1)), first_row,
                                      first_slot, ring_last, ring_size);
    const __m256i bottom_slot = ringSlot(lo, first_row, first_slot, ring_last, ring_size);
    __m256 sx, sy, sz;
    if (sameInEveryLane(top_slot) && sameInEveryLane(bottom_slot)) {
      // No box of the eight is clipped differently (inside a surface, most pixels): both
      // prefix rows are one row each, read as eight consecutive points, not gathered.
      const std::size_t top_row = static_cast<std::size_t>(_mm256_cvtsi256_si32(top_slot)) * w;
      const std::size_t bottom_row =
          static_cast<std::size_t>(_mm256_cvtsi256_si32(bottom_slot)) * w;
      __m256 tx, ty, tz, bx, by, bz;
      loadPoints8(prefix + top_row + u, tx, ty, tz);
      loadPoints8(prefix + bottom_row + u, bx, by, bz);
      sx = _mm256_sub_ps(tx, bx);
      sy = _mm256_sub_ps(ty, by);
      sz = _mm256_sub_ps(tz, bz);
    } else {
      const __m256i column = _mm256_add_epi32(_mm256_set1_epi32(3 * u), lane_floats);
      const __m256i top = _mm256_add_epi32(_mm256_mullo_epi32(top_slot, row_floats), column);
      const __m256i bottom = _mm256_add_epi32(_mm256_mullo_epi32(bottom_slot, row_floats), column);
      sx = _mm256_sub_ps(_mm256_i32gather_ps(table, top, 4), _mm256_i32gather_ps(table, bottom, 4));
      sy = _mm256_sub_ps(_mm256_i32gather_ps(table + 1, top, 4),
                         _mm256_i32gather_ps(table + 1, bottom, 4));
      sz = _mm256_sub_ps(_mm256_i32gather_ps(table + 2, top, 4),
                         _mm256_i32gather_ps(table + 2, bottom, 4));
    }
    const __m256 norm = _mm256_sqrt_ps(_mm256_add_ps(
        _mm256_mul_ps(sx, sx), _mm256_add_ps(_mm256_mul_ps(sy, sy), _mm256_mul_ps(sz, sz))));
    // Lanes without a normal, or whose sum nearly cancels, keep what they had.
    const __m256 take = _mm256_and_ps(has_normal, _mm256_cmp_ps(norm, min_norm, _CMP_GT_OQ));
    storePoints8(n + i, _mm256_blendv_ps(x, _mm256_div_ps(sx, norm), take),
                 _mm256_blendv_ps(y, _mm256_div_ps(sy, norm), take),
                 _mm256_blendv_ps(z, _mm256_div_ps(sz, norm), take));
  }
}

// The horizontal pass of smoothNormals for pixels u0 .. u0 + 7 of a row
// whose boxes are not clipped (every pixel from u0 - r to u0 + 7 + r in one
// run): row[u] = above[u] + (row_prefix[u + r + 1] - row_prefix[u - r]),
// Eigen's operations in Eigen's order, eight pixels at a time. The window of
// a pixel inside a run is a contiguous slice of the row prefix, so the loads
// are plain (no gathers).
__attribute__((target("avx2"))) void rowSumsAvx2(const Eigen::Vector3f* above,
                                                const Eigen::Vector3f* row_prefix,
                                                Eigen::Vector3f* row, int u0, int r) {
  __m256 ax, ay, az, hx, hy, hz, lx, ly, lz;
  loadPoints8(above + u0, ax, ay, az);
  loadPoints8(row_prefix + u0 + r + 1, hx, hy, hz);
  loadPoints8(row_prefix + u0 - r, lx, ly, lz);
  storePoints8(row + u0, _mm256_add_ps(ax, _mm256_sub_ps(hx, lx)),
               _mm256_add_ps(ay, _mm256_sub_ps(hy, ly)), _mm256_add_ps(az, _mm256_sub_ps(hz, lz)));
}

#endif

// Reusable buffers for the smoothing pass (see computeNormals).
struct SmoothingScratch {
  std::vector<float> depth;             // z of every point, contiguous
  std::vector<std::uint8_t> links;      // bit 0: linked to the right, bit 1: to below
  std::vector<Eigen::Vector3f> prefix;  // ring of 2r + 2 rows of the column prefix table
  std::vector<std::int32_t> run_start;  // first row of each pixel's vertical run
  std::vector<std::int32_t> run_end;    // last row of each pixel's vertical run
  std::vector<Eigen::Vector3f> row_prefix;
  std::vector<int> row_start;
};

constexpr std::uint8_t kLinkRight = 1;
constexpr std::uint8_t kLinkDown = 2;

// Links of a pixel at depth z to its right and lower neighbours: each when
// the depth step is at most max_jump_rel * z. None for a non-finite z (an
// infinite one would pass its own tolerance); a NaN anywhere fails the
// comparison. `down` is kLinkDown, or 0 on the last row.
inline std::uint8_t linkBits(float z, float right, float below, float max_jump_rel,
                             std::uint8_t down) {
  const float tol = max_jump_rel * z;
  // Bitwise, not && and ?:, so that the loops over a row vectorise.
  const int finite = std::abs(z) <= std::numeric_limits<float>::max();
  const int r = finite & (std::abs(right - z) <= tol);
  const int d = finite & (std::abs(below - z) <= tol);
  return static_cast<std::uint8_t>((r * kLinkRight) | (d * down));
}

// Replaces each finite entry of `n` by its box sum (radius r) over the finite
// entries, normalised (kept as it is where the sum nearly cancels). The box
// is clipped to the border AND to the pixel's surface: along each axis the
// window stops where two neighbouring pixels are not linked (one invalid, or
// a depth step larger than max_jump_rel * depth). So normals are averaged
// only with normals of the same surface, and a table edge does not bleed
// into the floor behind. Separable (rows, then columns) with prefix sums:
// O(1) per pixel for any r. The column prefix table is kept as a ring of the
// 2r + 2 rows a pixel row needs (tens of kB instead of 3.7 MB per VGA frame:
// it stays in cache), and the output goes straight back into `n`, row v once
// the row sums of every row up to v + r are in the ring (no later read of
// row v remains).
void smoothNormals(std::vector<Eigen::Vector3f>& n, const OrganizedCloud& cloud, int r,
                   float max_jump_rel, SmoothingScratch& s, bool avx2) {
  const int w = cloud.width;
  const int h = cloud.height;
  const std::size_t count = n.size();
  const Eigen::Vector3f* pts = cloud.points.data();
  if (count == 0) return;  // an empty grid (0 x h or w x 0): nothing to smooth

  // The links, from the depths copied out of the points: the loops below
  // are plain array loops over floats, which the compiler vectorises (on the
  // points' 12-byte stride it did not).
  s.depth.resize(count);
  for (std::size_t i = 0; i < count; ++i) s.depth[i] = pts[i].z();
  s.links.resize(count);
  for (int v = 0; v < h; ++v) {
    const std::size_t base = static_cast<std::size_t>(v) * w;
    const float* __restrict z = s.depth.data() + base;
    // The row below; the last row has none (compared with itself, unused).
    const float* __restrict below = v + 1 < h ? z + w : z;
    const std::uint8_t down = v + 1 < h ? kLinkDown : 0;
    std::uint8_t* __restrict links = s.links.data() + base;
    for (int u = 0; u + 1 < w; ++u) {
      links[u] = linkBits(z[u], z[u + 1], below[u], max_jump_rel, down);
    }
    links[w - 1] = linkBits(z[w - 1], std::numeric_limits<float>::quiet_NaN(), below[w - 1],
                            max_jump_rel, down);
  }
  // Vertical run ends, bottom to top (from the links alone).
  s.run_end.resize(count);
  for (int v = h - 1; v >= 0; --v) {
    const std::size_t base = static_cast<std::size_t>(v) * w;
    const std::uint8_t* __restrict links = s.links.data() + base;
    std::int32_t* __restrict end = s.run_end.data() + base;
    // Only read where linked down, so never beyond the last row.
    const std::int32_t* __restrict end_below = v + 1 < h ? end + w : end;
    for (int u = 0; u < w; ++u) {
      const std::int32_t below = end_below[u];  // unconditional: a select vectorises
      end[u] = (links[u] & kLinkDown) ? below : static_cast<std::int32_t>(v);
    }
  }

  // Prefix row k (k = 0..h) lives in ring slot k % ring.
  const int ring = 2 * r + 2;
  s.prefix.resize(static_cast<std::size_t>(ring) * w);
  const auto prefixRow = [&](int k) { return s.prefix.data() + static_cast<std::size_t>(k % ring) * w; };
  std::fill(prefixRow(0), prefixRow(0) + w, Eigen::Vector3f::Zero());
  s.row_prefix.resize(static_cast<std::size_t>(w) + 1);
  s.row_start.resize(static_cast<std::size_t>(w));
  s.run_start.resize(count);
  // Horizontal pass of image row v into prefix row v + 1.
  const auto addRow = [&](int v) {
    const std::size_t base = static_cast<std::size_t>(v) * w;
    const std::uint8_t* links = s.links.data() + base;
    const Eigen::Vector3f* above = prefixRow(v);
    Eigen::Vector3f* row = prefixRow(v + 1);
    // The running sum and run start are carried in locals: read back from
    // the arrays, each pixel waited for the previous pixel's store (the
    // compiler cannot tell the arrays from the normals they are built from).
    // The same additions in the same order.
    Eigen::Vector3f* __restrict row_prefix = s.row_prefix.data();
    int* __restrict row_start = s.row_start.data();
    Eigen::Vector3f running = Eigen::Vector3f::Zero();
    int start_here = 0;
    row_prefix[0] = running;
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3f& x = n[base + u];
      running = running + (std::isfinite(x.x()) ? x : Eigen::Vector3f::Zero());
      row_prefix[u + 1] = running;
      if (!(u > 0 && (links[u - 1] & kLinkRight))) start_here = u;
      row_start[u] = start_here;
    }
    // A loop of its own: element-wise, so it vectorises.
    std::int32_t* __restrict start = s.run_start.data() + base;
    if (v == 0) {
      std::fill(start, start + w, 0);
    } else {
      const std::uint8_t* __restrict links_above = s.links.data() + base - w;
      const std::int32_t* __restrict start_above = start - w;
      for (int u = 0; u < w; ++u) {
        const std::int32_t above = start_above[u];  // unconditional: a select vectorises
        start[u] = (links_above[u] & kLinkDown) ? above : v;
      }
    }
    // Right to left: the run end is known from the right neighbour.
    int row_end = w - 1;
    for (int u = w - 1; u >= 0;) {
#if defined(FINDMUG_AVX2_DISPATCH)
      // Eight pixels u - 7 .. u at once where every pixel from u - 7 - r to
      // u + 1 + r lies in one run (the run holding u + 1 + r started at or
      // before u - 7 - r): no box is clipped, and there is no run end among
      // them, so row_end stays what it is.
      if (avx2 && u - 7 >= r && u + 1 + r < w && s.row_start[u + 1 + r] <= u - 7 - r) {
        rowSumsAvx2(above, s.row_prefix.data(), row, u - 7, r);
        u -= 8;
        continue;
      }
#endif
      if (!(links[u] & kLinkRight)) row_end = u;
      const int lo = std::max(u - r, s.row_start[u]);
      const int hi = std::min(u + r, row_end);
      row[u] = above[u] + (s.row_prefix[hi + 1] - s.row_prefix[lo]);
      --u;
    }
  };

  int added = 0;  // image rows whose horizontal sums are in the ring
  for (int v = 0; v < h; ++v) {
    for (const int need = std::min(h - 1, v + r); added <= need; ++added) addRow(added);
    const std::size_t base = static_cast<std::size_t>(v) * w;
    int u = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
    if (avx2) {
      smoothColumnsAvx2(n.data(), s.run_start.data(), s.run_end.data(), s.prefix.data(), w, r, ring,
                        v, 0, w);
      u = w - w % 8;
    }
#else
    (void)avx2;
#endif
    for (; u < w; ++u) {
      const std::size_t i = base + u;
      if (!std::isfinite(n[i].x())) continue;
      const int lo = std::max(v - r, static_cast<int>(s.run_start[i]));
      const int hi = std::min(v + r, static_cast<int>(s.run_end[i]));
      const Eigen::Vector3f sum = prefixRow(hi + 1)[u] - prefixRow(lo)[u];
      const float norm = sum.norm();
      // The raw normal itself is in the sum, but opposite neighbours can
      // cancel it on a thin ridge; keep the raw one then.
      if (norm > 1e-3f) n[i] = sum / norm;
    }
  }
}

}  // namespace

OrganizedCloud frameToCloud(const RgbdFrame& frame, float max_depth_m) {
  OrganizedCloud cloud;
  frameToCloud(frame, max_depth_m, cloud);
  return cloud;
}

void frameToCloud(const RgbdFrame& frame, float max_depth_m, OrganizedCloud& cloud) {
  detail::frameToCloud(frame, max_depth_m, cloud, detail::CloudSimd::Auto);
}

namespace {

#if defined(FINDMUG_AVX2_DISPATCH)
// Pixels [0, width - width % 8) of one row of frameToCloud, eight at a time,
// with the scalar loop's float operations in its order; a pixel is valid when
// 0 < d <= max_mm, which for an integer d is d <= floor(max_mm)
// (`max_valid_mm`). Returns how many pixels were done.
__attribute__((target("avx2"))) int rowToPointsAvx2(const std::uint16_t* depth, int width,
                                                    float ray_y, float cx, float inv_fx,
                                                    int max_valid_mm, Eigen::Vector3f* out) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i zero = _mm256_setzero_si256(), limit = _mm256_set1_epi32(max_valid_mm);
  const __m256 nan = _mm256_set1_ps(std::numeric_limits<float>::quiet_NaN());
  const __m256 milli = _mm256_set1_ps(0.001f), vcx = _mm256_set1_ps(cx);
  const __m256 vfx = _mm256_set1_ps(inv_fx), vy = _mm256_set1_ps(ray_y);
  int u = 0;
  for (; u + 8 <= width; u += 8) {
    const __m256i d = _mm256_cvtepu16_epi32(
        _mm_loadu_si128(reinterpret_cast<const __m128i*>(depth + u)));
    const __m256i invalid =
        _mm256_or_si256(_mm256_cmpeq_epi32(d, zero), _mm256_cmpgt_epi32(d, limit));
    const __m256 z = _mm256_mul_ps(_mm256_cvtepi32_ps(d), milli);
    const __m256 ray_x = _mm256_mul_ps(
        _mm256_sub_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(u), lane)), vcx), vfx);
    const __m256 mask = _mm256_castsi256_ps(invalid);
    detail::storeVec3x8(out[u].data(), _mm256_blendv_ps(_mm256_mul_ps(ray_x, z), nan, mask),
                        _mm256_blendv_ps(_mm256_mul_ps(vy, z), nan, mask),
                        _mm256_blendv_ps(z, nan, mask));
  }
  return u;
}
#endif

}  // namespace

void detail::frameToCloud(const RgbdFrame& frame, float max_depth_m, OrganizedCloud& cloud,
                          CloudSimd simd) {
  validateFrame(frame);
  if (!std::isfinite(max_depth_m) || max_depth_m <= 0.0f) {
    throw Error((frame.source.empty() ? std::string("frameToCloud") : frame.source) +
                ": invalid max_depth_m " + std::to_string(max_depth_m));
  }
  cloud.width = frame.width;
  cloud.height = frame.height;
  const std::size_t pixels = static_cast<std::size_t>(frame.width) * frame.height;
  cloud.points.resize(pixels);
  cloud.colors = frame.rgb;

  const auto& k = frame.intrinsics;
  const float inv_fx = static_cast<float>(1.0 / k.fx);
  const float inv_fy = static_cast<float>(1.0 / k.fy);
  const float cx = static_cast<float>(k.cx);
  const float cy = static_cast<float>(k.cy);
  // Compare in millimetres so the hot loop has no float conversion for
  // rejected pixels.
  const double max_mm = static_cast<double>(max_depth_m) * 1000.0;
  bool avx2 = false;
#if defined(FINDMUG_AVX2_DISPATCH)
  avx2 = simd == detail::CloudSimd::Auto && detail::cpuHasAvx2();
  // The largest valid depth as an integer, for the integer compare.
  const int max_valid_mm = static_cast<int>(std::min(std::floor(max_mm), 65535.0));
#else
  (void)simd;
#endif

  for (int v = 0; v < frame.height; ++v) {
    const float ray_y = (static_cast<float>(v) - cy) * inv_fy;
    const std::size_t row = static_cast<std::size_t>(v) * frame.width;
    int u = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
    if (avx2) {
      u = rowToPointsAvx2(frame.depth_mm.data() + row, frame.width, ray_y, cx, inv_fx,
                          max_valid_mm, cloud.points.data() + row);
    }
#else
    (void)avx2;
#endif
    for (; u < frame.width; ++u) {
      const std::uint16_t d = frame.depth_mm[row + u];
      if (d == 0 || d > max_mm) {
        cloud.points[row + u] = kNaNVector;
        continue;
      }
      const float z = static_cast<float>(d) * 0.001f;
      const float ray_x = (static_cast<float>(u) - cx) * inv_fx;
      cloud.points[row + u] = Eigen::Vector3f(ray_x * z, ray_y * z, z);
    }
  }
}

NormalImage computeNormals(const OrganizedCloud& cloud, const NormalConfig& config) {
  NormalImage out;
  computeNormals(cloud, config, out);
  return out;
}

void computeNormals(const OrganizedCloud& cloud, const NormalConfig& config, NormalImage& out) {
  detail::computeNormals(cloud, config, out, detail::CloudSimd::Auto);
}

void detail::computeNormals(const OrganizedCloud& cloud, const NormalConfig& config,
                            NormalImage& out, CloudSimd simd) {
  checkCloudShape(cloud, "computeNormals");
  if (config.window_radius_px < 1 || config.window_radius_px > 64) {
    throw Error("computeNormals: normals.window_radius_px must be in 1..64, got " +
                std::to_string(config.window_radius_px));
  }
  if (config.smoothing_radius_px < 0 || config.smoothing_radius_px > 64) {
    throw Error("computeNormals: normals.smoothing_radius_px must be in 0..64, got " +
                std::to_string(config.smoothing_radius_px));
  }
  if (!std::isfinite(config.max_depth_jump_m) || config.max_depth_jump_m <= 0.0f) {
    throw Error("computeNormals: normals.max_depth_jump_m must be positive, got " +
                std::to_string(config.max_depth_jump_m));
  }
  const int w = cloud.width;
  const int h = cloud.height;
  const int r = config.window_radius_px;
  const Eigen::Vector3f* pts = cloud.points.data();

  out.width = w;
  out.height = h;
  out.normals.assign(cloud.points.size(), kNaNVector);
  std::vector<Eigen::Vector3f>& n = out.normals;

  // 1. Raw normals from differences at +-r pixels, oriented towards the
  //    camera (rawNormal).
  (void)simd;  // no SIMD path on this platform
#if defined(FINDMUG_AVX2_DISPATCH)
  if (simd == detail::CloudSimd::Auto && detail::cpuHasAvx2()) {
    rawNormalsAvx2(pts, w, h, r, config.max_depth_jump_m, n.data());
  } else
#endif
  {
    for (int v = 0; v < h; ++v) {
      rawNormalsScalar(pts, w, h, r, config.max_depth_jump_m, v, 0, w, n.data());
    }
  }

  // 2. Box-average the raw normals and renormalise. Pixels that had no raw
  //    normal stay NaN: they are isolated or on a depth edge.
  const int smooth_r = config.smoothing_radius_px;
  if (smooth_r > 0) {
    // Per-thread scratch: reusing it saves the page faults of several fresh
    // multi-megabyte buffers per 640x480 frame (a quarter of the run time).
    // It costs ~3 MB per thread that ever computed normals of a VGA frame.
    thread_local SmoothingScratch scratch;
    bool avx2 = false;
#if defined(FINDMUG_AVX2_DISPATCH)
    avx2 = simd == detail::CloudSimd::Auto && detail::cpuHasAvx2();
#endif
    smoothNormals(n, cloud, smooth_r, config.max_depth_jump_m, scratch, avx2);
  }
}

OrganizedCloud transformCloud(const OrganizedCloud& cloud, const Eigen::Isometry3f& transform) {
  OrganizedCloud out;
  transformCloud(cloud, transform, out);
  return out;
}

void transformCloud(const OrganizedCloud& cloud, const Eigen::Isometry3f& transform,
                    OrganizedCloud& out) {
  detail::transformCloud(cloud, transform, out, detail::CloudSimd::Auto);
}

NormalImage rotateNormals(const NormalImage& normals, const Eigen::Matrix3f& rotation) {
  NormalImage out;
  rotateNormals(normals, rotation, out);
  return out;
}

void rotateNormals(const NormalImage& normals, const Eigen::Matrix3f& rotation, NormalImage& out) {
  detail::rotateNormals(normals, rotation, out, detail::CloudSimd::Auto);
}

namespace {

#if defined(FINDMUG_AVX2_DISPATCH)
// rotation * v (+ translation) of `count` vectors, eight at a time, with
// Eigen's operations in Eigen's order: each row is r0 x + (r1 y + r2 z), then
// the translation is added. A vector whose `finite_axis` coordinate is not
// finite becomes NaN, as in the portable loops. Returns how many were done
// (a multiple of eight); the caller does the rest.
__attribute__((target("avx2"))) std::size_t transformVec3Avx2(
    const Eigen::Vector3f* in, std::size_t count, const Eigen::Matrix3f& rotation,
    const Eigen::Vector3f* translation, int finite_axis, Eigen::Vector3f* out) {
  __m256 r[3][3];
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) r[row][col] = _mm256_set1_ps(rotation(row, col));
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 infinity = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 nan = _mm256_set1_ps(std::numeric_limits<float>::quiet_NaN());
  std::size_t k = 0;
  for (; k + 8 <= count; k += 8) {
    __m256 v[3];
    detail::loadVec3x8(in[k].data(), v[0], v[1], v[2]);
    // Finite: |c| < infinity (false for NaN, as std::isfinite). Selected, not
    // indexed: v[finite_axis] made the compiler keep v on the stack.
    const __m256 tested = finite_axis == 0 ? v[0] : finite_axis == 1 ? v[1] : v[2];
    const __m256 finite = _mm256_cmp_ps(_mm256_and_ps(tested, abs_mask), infinity, _CMP_LT_OQ);
    __m256 o[3];
    for (int row = 0; row < 3; ++row) {
      o[row] = detail::dot3x8(r[row][0], r[row][1], r[row][2], v[0], v[1], v[2]);
      if (translation) o[row] = _mm256_add_ps(o[row], _mm256_set1_ps((*translation)[row]));
      o[row] = _mm256_blendv_ps(nan, o[row], finite);
    }
    detail::storeVec3x8(out[k].data(), o[0], o[1], o[2]);
  }
  return k;
}
#endif

}  // namespace

void detail::transformCloud(const OrganizedCloud& cloud, const Eigen::Isometry3f& transform,
                            OrganizedCloud& out, CloudSimd simd) {
  out.width = cloud.width;
  out.height = cloud.height;
  out.colors = cloud.colors;
  out.points.resize(cloud.points.size());
  const Eigen::Matrix3f rotation = transform.linear();
  const Eigen::Vector3f translation = transform.translation();
  std::size_t done = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
  if (simd == CloudSimd::Auto && cpuHasAvx2()) {
    done = transformVec3Avx2(cloud.points.data(), cloud.points.size(), rotation, &translation, 2,
                             out.points.data());
  }
#endif
  (void)simd;
  for (std::size_t i = done; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    out.points[i] = std::isfinite(p.z()) ? Eigen::Vector3f(rotation * p + translation) : kNaNVector;
  }
}

void detail::rotateNormals(const NormalImage& normals, const Eigen::Matrix3f& rotation,
                           NormalImage& out, CloudSimd simd) {
  out.width = normals.width;
  out.height = normals.height;
  out.normals.resize(normals.normals.size());
  std::size_t done = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
  if (simd == CloudSimd::Auto && cpuHasAvx2()) {
    done = transformVec3Avx2(normals.normals.data(), normals.normals.size(), rotation, nullptr, 0,
                             out.normals.data());
  }
#endif
  (void)simd;
  for (std::size_t i = done; i < normals.normals.size(); ++i) {
    const Eigen::Vector3f& n = normals.normals[i];
    out.normals[i] = std::isfinite(n.x()) ? Eigen::Vector3f(rotation * n) : kNaNVector;
  }
}

}  // namespace findmug
