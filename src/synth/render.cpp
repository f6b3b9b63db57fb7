// Ray casting renderer for synthetic apartment scenes.
//
// Speed strategy (target: 640x480 well under 50 ms on one core):
//  1. The room shell (floor, ceiling, four walls) is an axis-aligned box seen
//     from inside: every ray leaves it, so one slab exit test per pixel gives
//     the background depth.
//  2. Each furniture/object primitive is tested only on the pixels of its
//     screen bounding box (its 3-D bounds clipped at the near plane and
//     projected), z-buffer style, with the ray pre-rotated into the
//     primitive's yaw frame. Small things (mugs, legs) cost a few hundred rays.
//  3. Shading, labels and the depth noise model run once per pixel on the
//     winning hit (deferred), so hidden surfaces are never shaded.
//  4. Per frame, not per pixel: each primitive's pose in floats; the trace
//     buffers are kept per thread. Same bits as before.
//  5. countObjectPixels runs steps 1-2 only, on the union of one object's
//     screen boxes: what an oracle recogniser needs, not a whole frame.
// Ray directions are scaled so their optical-axis component is 1: the ray
// parameter t IS the depth z the sensor reports.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/synth/synth.hpp"
#include "synth_internal.hpp"

namespace findmug::synth {

namespace detail {

namespace {
constexpr int kTableBits = 12;
constexpr int kTableSize = 1 << kTableBits;

double normalCdf(double x) { return 0.5 * std::erfc(-x / M_SQRT2); }

double inverseNormalCdf(double p) {
  double lo = -10.0, hi = 10.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (normalCdf(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Inverse CDF at p = k / kTableSize (ends pulled in to p = 0.25 / kTableSize).
const std::array<float, kTableSize + 1>& inverseCdfTable() {
  static const std::array<float, kTableSize + 1> table = [] {
    std::array<float, kTableSize + 1> t{};
    for (int k = 0; k <= kTableSize; ++k) {
      const double p = k == 0            ? 0.25 / kTableSize
                       : k == kTableSize ? 1.0 - 0.25 / kTableSize
                                         : static_cast<double>(k) / kTableSize;
      t[k] = static_cast<float>(inverseNormalCdf(p));
    }
    return t;
  }();
  return table;
}

// Standard normal from 21 uniform bits: 12 pick the table cell, 9 interpolate.
inline float gaussianFrom21(const std::array<float, kTableSize + 1>& table, std::uint32_t bits) {
  const std::uint32_t k = bits >> 9;
  const float frac = static_cast<float>(bits & 511u) * (1.0f / 512.0f);
  return table[k] + frac * (table[k + 1] - table[k]);
}
}  // namespace

double gaussianFromBits(std::uint64_t bits) {
  return gaussianFrom21(inverseCdfTable(), static_cast<std::uint32_t>(bits >> 43));
}

}  // namespace detail

namespace {

constexpr float kNear = 0.02f;  // metres; nothing closer is rendered
constexpr float kInf = std::numeric_limits<float>::infinity();

struct V3 {
  float x, y, z;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(float s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 rotZ(V3 a, float c, float s) { return {c * a.x - s * a.y, s * a.x + c * a.y, a.z}; }

float fract(float x) { return x - std::floor(x); }

// Uniform [0,1) from integer lattice coordinates (for per-board/tile tones).
float latticeHash(std::int64_t a, std::int64_t b, std::uint64_t salt) {
  return static_cast<float>(detail::toUnit(
      detail::hash3(static_cast<std::uint64_t>(a), static_cast<std::uint64_t>(b), salt)));
}

// Procedural texture: a brightness factor for a point. `world` is the hit
// point, `local` the same point in the primitive's frame, `axis` the index of
// the local face normal (0 x, 1 y, 2 z).
float textureFactor(const Material& m, V3 world, V3 local, int axis, std::uint64_t salt) {
  const float s = std::max(m.texture_scale_m, 1e-3f);
  switch (m.texture) {
    case Texture::Plain:
      return 1.0f;
    case Texture::Wood: {
      // Grain runs along local x: stripes across y (top) or z (sides).
      const float across = axis == 2 ? local.y : local.z;
      const float phase = (across + 0.04f * std::sin(local.x * 7.0f)) * (6.2831853f / s);
      return 1.0f + 0.07f * std::sin(phase) + 0.04f * std::sin(2.3f * phase + 1.0f);
    }
    case Texture::Planks: {
      const float board = std::floor(world.y / s);
      const float offset = latticeHash(static_cast<std::int64_t>(board), 7, salt) * 1.2f;
      const float along = (world.x + offset) / 1.2f;
      const float seg = std::floor(along);
      if (fract(world.y / s) < 0.03f || fract(along) < 0.004f) return 0.6f;  // seams
      const float tone = 0.88f + 0.24f * latticeHash(static_cast<std::int64_t>(board),
                                                     static_cast<std::int64_t>(seg), salt);
      return tone * (1.0f + 0.05f * std::sin(world.y * 160.0f + 3.0f * std::sin(world.x * 2.0f)));
    }
    case Texture::Tiles: {
      const float u = world.x / s, v = world.y / s;
      if (fract(u) < 0.015f || fract(v) < 0.015f) return 0.78f;  // grout
      return 0.94f + 0.12f * latticeHash(static_cast<std::int64_t>(std::floor(u)),
                                         static_cast<std::int64_t>(std::floor(v)), salt);
    }
    case Texture::Carpet: {
      return 0.9f + 0.2f * latticeHash(static_cast<std::int64_t>(std::floor(world.x / s)),
                                       static_cast<std::int64_t>(std::floor(world.y / s)), salt);
    }
    case Texture::Panel:
      // A dark seam between two doors on the front/back faces (local y normal).
      if (axis == 1 && std::abs(local.x) < 0.004f) return 0.45f;
      return 1.0f;
  }
  return 1.0f;
}

struct PrimitiveSetup {
  float cos_yaw, sin_yaw;  // local = Rz(-yaw) * (world - centre)
  V3 center, half;
  V3 origin_local;
  V3 c0, c1, c2;  // the camera-to-world columns rotated into the local frame
  bool cylinder;
};

// Screen bounding box of a primitive: its bounding box corners clipped at the
// near plane and projected. Returns false when it is entirely behind.
bool screenBounds(const Primitive& p, const Eigen::Isometry3d& world_to_camera,
                  const CameraIntrinsics& k, int width, int height, int& u0, int& u1, int& v0,
                  int& v1) {
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  const Eigen::Vector3d& h = p.half_extent;
  std::array<Eigen::Vector3d, 8> corners;
  for (int i = 0; i < 8; ++i) {
    const double lx = (i & 1) ? h.x() : -h.x();
    const double ly = (i & 2) ? h.y() : -h.y();
    const double lz = (i & 4) ? h.z() : -h.z();
    const Eigen::Vector3d w = p.center + Eigen::Vector3d(c * lx - s * ly, s * lx + c * ly, lz);
    corners[i] = world_to_camera * w;
  }
  double umin = 1e30, umax = -1e30, vmin = 1e30, vmax = -1e30;
  bool any = false;
  auto add = [&](const Eigen::Vector3d& q) {
    const double u = k.fx * q.x() / q.z() + k.cx, v = k.fy * q.y() / q.z() + k.cy;
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
    any = true;
  };
  for (const auto& q : corners)
    if (q.z() >= kNear) add(q);
  // Edges of the box differ in exactly one bit of the corner index.
  for (int a = 0; a < 8; ++a) {
    for (int bit = 1; bit < 8; bit <<= 1) {
      const int b = a | bit;
      if (b == a) continue;
      const Eigen::Vector3d& qa = corners[a];
      const Eigen::Vector3d& qb = corners[b];
      if ((qa.z() < kNear) != (qb.z() < kNear)) {
        const double t = (kNear - qa.z()) / (qb.z() - qa.z());
        add(qa + t * (qb - qa));
      }
    }
  }
  if (!any) return false;
  u0 = static_cast<int>(std::max(0.0, std::floor(umin) - 1));
  v0 = static_cast<int>(std::max(0.0, std::floor(vmin) - 1));
  u1 = static_cast<int>(std::min<double>(width - 1, std::ceil(umax) + 1));
  v1 = static_cast<int>(std::min<double>(height - 1, std::ceil(vmax) + 1));
  return u0 <= u1 && v0 <= v1;
}

}  // namespace

void validate(const RenderOptions& o) {
  std::ostringstream msg;
  const auto& k = o.intrinsics;
  const auto& n = o.noise;
  if (o.width <= 0 || o.height <= 0 || o.width > 4096 || o.height > 4096) {
    msg << "synth: absurd image size " << o.width << "x" << o.height;
  } else if (!(std::isfinite(k.fx) && std::isfinite(k.fy) && std::isfinite(k.cx) &&
               std::isfinite(k.cy) && k.fx > 0 && k.fy > 0)) {
    msg << "synth: invalid intrinsics fx=" << k.fx << " fy=" << k.fy << " cx=" << k.cx
        << " cy=" << k.cy;
  } else if (!(n.min_range_m >= 0.0 && n.min_range_m < n.max_range_m && n.max_range_m <= 65.0)) {
    msg << "synth: invalid depth range [" << n.min_range_m << ", " << n.max_range_m << "] m";
  } else if (!(n.disparity_k > 0.0 && n.disparity_k < 1.0)) {
    msg << "synth: invalid disparity_k " << n.disparity_k;
  } else if (!(n.disparity_sigma >= 0.0 && n.disparity_sigma < 100.0)) {
    msg << "synth: invalid disparity_sigma " << n.disparity_sigma;
  } else if (!(n.grazing_start_deg >= 0.0 && n.grazing_start_deg < n.grazing_full_deg &&
               n.grazing_full_deg <= 90.0)) {
    msg << "synth: invalid grazing angles " << n.grazing_start_deg << ".." << n.grazing_full_deg;
  } else if (!(n.projector_baseline_m >= 0.0 && n.projector_baseline_m < 1.0)) {
    msg << "synth: invalid projector_baseline_m " << n.projector_baseline_m;
  } else if (!(n.rgb_noise_sigma >= 0.0 && n.rgb_noise_sigma < 100.0)) {
    msg << "synth: invalid rgb_noise_sigma " << n.rgb_noise_sigma;
  } else {
    return;
  }
  throw Error(msg.str());
}

namespace {

// std::round (halves away from zero) without the libm call, which took a few per cent of
// a frame's render (two per pixel). The same value for every double: from 2^52 on every
// double is an integer, and NaN and infinities pass through as std::round leaves them.
// The half is added as a 0 or 1, not chosen by a branch: on noisy disparities that branch
// went either way at random, and its mispredictions cost more than the rest of a sample.
inline double roundHalfAwayFromZero(double x) {
  const double magnitude = std::abs(x);
  if (!(magnitude < 0x1p52)) return x;
  const double whole = static_cast<double>(static_cast<std::int64_t>(magnitude));
  return std::copysign(whole + static_cast<double>(magnitude - whole >= 0.5), x);
}

}  // namespace

namespace {

// The millimetre sample of a disparity (after any quantising; > 0).
inline std::uint16_t depthOfDisparityMm(double disparity, const DepthNoiseParams& noise) {
  const double mm = roundHalfAwayFromZero(1000.0 / (noise.disparity_k * disparity));
  return mm >= 1.0 && mm <= 65535.0 ? static_cast<std::uint16_t>(mm) : 0;
}

}  // namespace

std::uint16_t noisyDepthMm(double z_m, const DepthNoiseParams& noise, double gaussian) {
  if (!(z_m >= noise.min_range_m && z_m <= noise.max_range_m)) return 0;
  double disparity = 1.0 / (noise.disparity_k * z_m) + noise.disparity_sigma * gaussian;
  if (noise.quantise) disparity = roundHalfAwayFromZero(disparity);
  if (disparity <= 0.0) return 0;
  return depthOfDisparityMm(disparity, noise);
}

NoisyDepthSampler::NoisyDepthSampler(const DepthNoiseParams& noise) : noise_(noise) {
  if (!noise.quantise || !(noise.min_range_m > 0.0) || !(noise.disparity_k > 0.0)) return;
  // The levels of the nearest depth in range, with eight sigmas of noise to spare (the
  // renderer's normal samples stay within about 5.3), at most 2^16 of them.
  const double highest =
      1.0 / (noise.disparity_k * noise.min_range_m) + 8.0 * std::abs(noise.disparity_sigma);
  if (!(highest >= 1.0)) return;
  const auto levels = static_cast<std::size_t>(std::min(highest, 65535.0)) + 1;
  level_mm_.resize(levels);
  for (std::size_t d = 1; d < levels; ++d)
    level_mm_[d] = depthOfDisparityMm(static_cast<double>(d), noise);
}

std::uint16_t NoisyDepthSampler::operator()(double z_m, double gaussian) const {
  if (level_mm_.empty()) return noisyDepthMm(z_m, noise_, gaussian);
  if (!(z_m >= noise_.min_range_m && z_m <= noise_.max_range_m)) return 0;
  const double disparity =
      roundHalfAwayFromZero(1.0 / (noise_.disparity_k * z_m) + noise_.disparity_sigma * gaussian);
  if (disparity <= 0.0) return 0;
  // An integer here (quantised); below the table's size it is one of its levels.
  if (disparity < static_cast<double>(level_mm_.size()))
    return level_mm_[static_cast<std::size_t>(disparity)];
  return depthOfDisparityMm(disparity, noise_);
}

namespace {

// The camera's rays: through pixel (u, v) d = a[u] * c0 + b[v] * c1 + c2 (optical z
// component 1), from o, all in the world frame.
struct Rays {
  V3 o, c0, c1, c2;
  std::vector<float> a, b;
};

Rays raysOf(const Eigen::Isometry3d& cam_to_world, const CameraIntrinsics& K, int W, int H) {
  Rays r;
  const Eigen::Vector3d o_d = cam_to_world.translation();
  const Eigen::Matrix3d& Rd = cam_to_world.linear();
  r.o = {static_cast<float>(o_d.x()), static_cast<float>(o_d.y()), static_cast<float>(o_d.z())};
  auto col = [&](int c) {
    return V3{static_cast<float>(Rd(0, c)), static_cast<float>(Rd(1, c)),
              static_cast<float>(Rd(2, c))};
  };
  r.c0 = col(0);
  r.c1 = col(1);
  r.c2 = col(2);
  r.a.resize(W);
  r.b.resize(H);
  for (int u = 0; u < W; ++u) r.a[u] = static_cast<float>((u - K.cx) / K.fx);
  for (int v = 0; v < H; ++v) r.b[v] = static_cast<float>((v - K.cy) / K.fy);
  return r;
}

// The pixels [u0, u1] x [v0, v1] whose depths and hits a trace keeps, in row-major buffers
// of (u1 - u0 + 1) columns: the whole image for a frame, less when only some pixels matter
// (countObjectPixels). A pixel's ray and its tests do not depend on the region.
struct Region {
  int u0, u1, v0, v1;
  int columns() const { return u1 - u0 + 1; }
  std::size_t pixels() const { return static_cast<std::size_t>(columns()) * (v1 - v0 + 1); }
  std::size_t index(int u, int v) const {
    return static_cast<std::size_t>(v - v0) * columns() + (u - u0);
  }
};

// Step 1: the room shell: exit point of the box [0,X]x[0,Y]x[0,Hc] (hit = -1 - surface).
void traceShell(const Rays& r, float X, float Y, float Hc, const Region region, float* zbuf,
                std::int32_t* hit) {
  const V3 o = r.o;
  for (int v = region.v0; v <= region.v1; ++v) {
    const V3 base = r.b[v] * r.c1 + r.c2;
    float* zrow = zbuf + region.index(region.u0, v);
    std::int32_t* hrow = hit + region.index(region.u0, v);
    for (int u = region.u0; u <= region.u1; ++u) {
      const V3 d = r.a[u] * r.c0 + base;
      float t = kInf;
      int surface = 0;
      auto consider = [&](float dc, float oc, float hi, int s_lo, int s_hi) {
        if (dc > 0.0f) {
          const float tt = (hi - oc) / dc;
          if (tt < t) {
            t = tt;
            surface = s_hi;
          }
        } else if (dc < 0.0f) {
          const float tt = -oc / dc;
          if (tt < t) {
            t = tt;
            surface = s_lo;
          }
        }
      };
      consider(d.z, o.z, Hc, 0, 1);  // floor / ceiling
      consider(d.x, o.x, X, 2, 3);   // walls x = 0 / x = X
      consider(d.y, o.y, Y, 4, 5);   // walls y = 0 / y = Y
      zrow[u - region.u0] = t;
      hrow[u - region.u0] = -1 - surface;
    }
  }
}

// Step 2: one primitive over its screen bounding box [u0, u1] x [v0, v1] (within the
// region), nearer hits replacing farther ones.
void tracePrimitive(const Primitive& p, std::int32_t id, const Rays& r, int u0, int u1, int v0,
                    int v1, const Region region, float* zbuf, std::int32_t* hit) {
  const float cy = static_cast<float>(std::cos(p.yaw)), sy = static_cast<float>(std::sin(p.yaw));
  const V3 center{static_cast<float>(p.center.x()), static_cast<float>(p.center.y()),
                  static_cast<float>(p.center.z())};
  const V3 half{static_cast<float>(p.half_extent.x()), static_cast<float>(p.half_extent.y()),
                static_cast<float>(p.half_extent.z())};
  // Rotate by -yaw into the primitive's frame.
  const V3 ol = rotZ(r.o - center, cy, -sy);
  const V3 l0 = rotZ(r.c0, cy, -sy), l1 = rotZ(r.c1, cy, -sy), l2 = rotZ(r.c2, cy, -sy);
  if (p.shape == Shape::Box) {
    for (int v = v0; v <= v1; ++v) {
      const V3 base = r.b[v] * l1 + l2;
      float* zrow = zbuf + region.index(u0, v);
      std::int32_t* hrow = hit + region.index(u0, v);
      for (int u = u0; u <= u1; ++u) {
        const V3 d = r.a[u] * l0 + base;
        const float ix = 1.0f / d.x, iy = 1.0f / d.y, iz = 1.0f / d.z;
        const float tx1 = (-half.x - ol.x) * ix, tx2 = (half.x - ol.x) * ix;
        const float ty1 = (-half.y - ol.y) * iy, ty2 = (half.y - ol.y) * iy;
        const float tz1 = (-half.z - ol.z) * iz, tz2 = (half.z - ol.z) * iz;
        const float tmin =
            std::max(std::max(std::min(tx1, tx2), std::min(ty1, ty2)), std::min(tz1, tz2));
        const float tmax =
            std::min(std::min(std::max(tx1, tx2), std::max(ty1, ty2)), std::max(tz1, tz2));
        if (tmin <= tmax && tmin > kNear && tmin < zrow[u - u0]) {
          zrow[u - u0] = tmin;
          hrow[u - u0] = id;
        }
      }
    }
    return;
  }
  const float r2 = half.x * half.x;
  const float cxy = ol.x * ol.x + ol.y * ol.y - r2;
  for (int v = v0; v <= v1; ++v) {
    const V3 base = r.b[v] * l1 + l2;
    float* zrow = zbuf + region.index(u0, v);
    std::int32_t* hrow = hit + region.index(u0, v);
    for (int u = u0; u <= u1; ++u) {
      const V3 d = r.a[u] * l0 + base;
      float t = kInf;
      const float qa = d.x * d.x + d.y * d.y;
      const float qb = ol.x * d.x + ol.y * d.y;
      const float disc = qb * qb - qa * cxy;
      if (qa > 0.0f && disc >= 0.0f) {
        const float ts = (-qb - std::sqrt(disc)) / qa;
        const float zs = ol.z + ts * d.z;
        if (ts > kNear && std::abs(zs) <= half.z) t = ts;
      }
      // The cap facing the camera.
      const float cap = ol.z > half.z ? half.z : (ol.z < -half.z ? -half.z : 0.0f);
      if (cap != 0.0f && d.z != 0.0f) {
        const float tc = (cap - ol.z) / d.z;
        const float x = ol.x + tc * d.x, y = ol.y + tc * d.y;
        if (tc > kNear && tc < t && x * x + y * y <= r2) t = tc;
      }
      if (t < zrow[u - u0]) {
        zrow[u - u0] = t;
        hrow[u - u0] = id;
      }
    }
  }
}

// Step 3: projector shadows (see synth.hpp): row-wise scan from the projector side.
void projectorShadows(const std::vector<float>& zbuf, const CameraIntrinsics& K,
                      const DepthNoiseParams& noise, int W, int H,
                      std::vector<std::uint8_t>& shadow) {
  shadow.assign(zbuf.size(), 0);
  if (!(noise.enabled && noise.projector_shadows && noise.projector_baseline_m > 0.0)) {
    return;
  }
  const float fb = static_cast<float>(K.fx * noise.projector_baseline_m);
  for (int v = 0; v < H; ++v) {
    float min_col = kInf;
    for (int u = W - 1; u >= 0; --u) {
      const std::size_t i = static_cast<std::size_t>(v) * W + u;
      const float col_p = static_cast<float>(u) - fb / zbuf[i];
      if (col_p >= min_col) shadow[i] = 1;
      min_col = std::min(min_col, col_p);
    }
  }
}

// What a ray hit at P: the surface's normal, material, object, the point in the
// primitive's own frame (texture coordinates), its dominant axis and texture salt.
struct SurfaceHit {
  V3 n, local;
  int axis = 2;
  const Material* m = nullptr;
  int object = 0;
  std::uint64_t salt = 0;
};

// A primitive's pose in the renderer's floats, worked out once per frame rather than once
// per pixel (the same conversions, so the same bits).
struct PrimitiveFrame {
  float cos_yaw, sin_yaw;
  V3 center, half;
};

std::vector<PrimitiveFrame> primitiveFrames(const SynthScene& scene) {
  std::vector<PrimitiveFrame> out;
  out.reserve(scene.primitives.size());
  for (const Primitive& p : scene.primitives)
    out.push_back({static_cast<float>(std::cos(p.yaw)), static_cast<float>(std::sin(p.yaw)),
                   V3{static_cast<float>(p.center.x()), static_cast<float>(p.center.y()),
                      static_cast<float>(p.center.z())},
                   V3{static_cast<float>(p.half_extent.x()), static_cast<float>(p.half_extent.y()),
                      static_cast<float>(p.half_extent.z())}});
  return out;
}

SurfaceHit surfaceAt(const SynthScene& scene, const std::vector<PrimitiveFrame>& frames,
                     std::int32_t hit, const V3& P) {
  static const std::array<V3, 6> kShellNormals = {
      {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}}};
  SurfaceHit h;
  if (hit < 0) {
    const int s = -1 - hit;
    h.n = kShellNormals[s];
    h.object = s;  // objects 0..5 are floor, ceiling and the walls in this order
    h.m =
        s == 0 ? &scene.floor_material : (s == 1 ? &scene.ceiling_material : &scene.wall_material);
    h.local = P;
    h.salt = scene.seed;
    return h;
  }
  const Primitive& p = scene.primitives[hit];
  const PrimitiveFrame& f = frames[hit];
  const float cy = f.cos_yaw, sy = f.sin_yaw;
  const V3 local = rotZ(P - f.center, cy, -sy);
  const float hx = f.half.x, hy = f.half.y, hz = f.half.z;
  V3 nl;
  if (p.shape == Shape::Box) {
    const float ex = std::abs(local.x) / hx, ey = std::abs(local.y) / hy,
                ez = std::abs(local.z) / hz;
    if (ex >= ey && ex >= ez) {
      nl = {local.x > 0 ? 1.0f : -1.0f, 0, 0};
      h.axis = 0;
    } else if (ey >= ez) {
      nl = {0, local.y > 0 ? 1.0f : -1.0f, 0};
      h.axis = 1;
    } else {
      nl = {0, 0, local.z > 0 ? 1.0f : -1.0f};
      h.axis = 2;
    }
  } else {
    const float radial = std::sqrt(local.x * local.x + local.y * local.y);
    if (std::abs(hz - std::abs(local.z)) < std::abs(hx - radial)) {
      nl = {0, 0, local.z > 0 ? 1.0f : -1.0f};
      h.axis = 2;
    } else {
      nl = {local.x / radial, local.y / radial, 0};
      h.axis = 0;
    }
  }
  h.n = rotZ(nl, cy, sy);
  h.local = local;
  h.m = &p.material;
  h.object = p.object;
  h.salt = static_cast<std::uint64_t>(hit) * 0x9e3779b9ULL + scene.seed;
  return h;
}

// Step 4: per-pixel shading, labels and depth noise into `out` (sized by the caller).
void shadePixels(const SynthScene& scene, const Rays& r, const std::vector<float>& zbuf,
                 const std::vector<std::int32_t>& hit, const std::vector<std::uint8_t>& shadow,
                 const RenderOptions& options, float X, float Y, float Hc, std::uint64_t noise_seed,
                 RenderedFrame& out) {
  const int W = options.width, H = options.height;
  const DepthNoiseParams& noise = options.noise;
  RgbdFrame& frame = out.labeled.frame;
  const auto& gauss_table = detail::inverseCdfTable();
  const float cos_start = static_cast<float>(std::cos(noise.grazing_start_deg * M_PI / 180.0));
  const float cos_full = static_cast<float>(std::cos(noise.grazing_full_deg * M_PI / 180.0));
  const V3 light{X / 2, Y / 2, Hc - 0.05f};
  const float rgb_sigma = static_cast<float>(noise.rgb_noise_sigma);
  const std::uint64_t frame_key = detail::mix64(noise_seed ^ 0xd1b54a32d192ed03ULL);
  const std::vector<PrimitiveFrame> frames = primitiveFrames(scene);
  const NoisyDepthSampler noisy_depth_mm(noise);

  for (int v = 0; v < H; ++v) {
    const V3 base = r.b[v] * r.c1 + r.c2;
    for (int u = 0; u < W; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * W + u;
      const V3 d = r.a[u] * r.c0 + base;
      const float t = zbuf[i];
      const V3 P = r.o + t * d;
      const SurfaceHit s = surfaceAt(scene, frames, hit[i], P);

      // Colour: texture x (ambient + diffuse from a ceiling light) + sensor noise.
      const V3 to_light = light - P;
      const float dist2 = dot(to_light, to_light);
      const float diffuse = std::max(0.0f, dot(s.n, to_light)) / std::sqrt(dist2);
      const float shade =
          (0.38f + 0.8f * diffuse / (1.0f + 0.06f * dist2) + 0.15f * std::max(0.0f, -s.n.z)) *
          textureFactor(*s.m, P, s.local, s.axis, s.salt);
      const std::uint64_t h_rgb = detail::hash3(frame_key, i, 1);
      auto channel = [&](std::uint8_t c, int k) {
        const float g = detail::gaussianFrom21(
            gauss_table, static_cast<std::uint32_t>(h_rgb >> (43 - 21 * k)) & 0x1fffffu);
        const float value = c * shade + rgb_sigma * g;
        return static_cast<std::uint8_t>(std::clamp(value + 0.5f, 0.0f, 255.0f));
      };
      frame.rgb[i] = {channel(s.m->color.r, 0), channel(s.m->color.g, 1), channel(s.m->color.b, 2)};
      out.labeled.labels[i] = static_cast<std::uint8_t>(scene.objects[s.object].label);
      out.object[i] = s.object;
      out.true_depth_m[i] = t;

      // Depth: range, grazing dropout, projector shadow, disparity noise.
      if (!noise.enabled) {
        const float mm = std::round(t * 1000.0f);
        frame.depth_mm[i] = mm >= 1.0f && mm <= 65535.0f ? static_cast<std::uint16_t>(mm) : 0;
        continue;
      }
      if (shadow[i] || t < noise.min_range_m || t > noise.max_range_m) continue;
      const std::uint64_t h_depth = detail::hash3(frame_key, i, 2);
      const float cos_inc = std::abs(dot(s.n, d)) / std::sqrt(dot(d, d));
      if (cos_inc < cos_start) {
        const float p_drop = (cos_start - cos_inc) / (cos_start - cos_full);
        if (static_cast<float>(detail::toUnit(detail::mix64(h_depth))) < p_drop) continue;
      }
      frame.depth_mm[i] = noisy_depth_mm(
          t, detail::gaussianFrom21(gauss_table, static_cast<std::uint32_t>(h_depth >> 43)));
    }
  }
}

// The camera of one frame in the room: its rays and the transform primitives are projected
// with. Throws when the camera is outside the room.
struct View {
  Eigen::Isometry3d cam_to_world, world_to_cam;
  Rays rays;
  float X, Y, Hc;  // the room's box
};

View viewOf(const SynthScene& scene, const CameraPose& pose, const RenderOptions& options) {
  const Eigen::Vector3d room = scene.room_size;
  View view;
  view.cam_to_world = cameraToWorld(pose);
  const Eigen::Vector3d o_d = view.cam_to_world.translation();
  if (!(o_d.x() > 0 && o_d.y() > 0 && o_d.z() > 0 && o_d.x() < room.x() && o_d.y() < room.y() &&
        o_d.z() < room.z())) {
    std::ostringstream msg;
    msg << "synth: camera at (" << o_d.transpose() << ") is outside the room (" << room.transpose()
        << ")";
    throw Error(msg.str());
  }
  view.world_to_cam = view.cam_to_world.inverse();
  view.rays = raysOf(view.cam_to_world, options.intrinsics, options.width, options.height);
  view.X = static_cast<float>(room.x());
  view.Y = static_cast<float>(room.y());
  view.Hc = static_cast<float>(room.z());
  return view;
}

// Steps 1 and 2 on the pixels of `region`: depth and hit (primitive index, or -1 - shell
// surface) of every one, into buffers of region.pixels().
void traceRegion(const SynthScene& scene, const View& view, const RenderOptions& options,
                 const Region& region, std::vector<float>& zbuf, std::vector<std::int32_t>& hit) {
  zbuf.resize(region.pixels());
  hit.resize(region.pixels());
  traceShell(view.rays, view.X, view.Y, view.Hc, region, zbuf.data(), hit.data());
  for (std::size_t pi = 0; pi < scene.primitives.size(); ++pi) {
    int u0, u1, v0, v1;
    if (!screenBounds(scene.primitives[pi], view.world_to_cam, options.intrinsics, options.width,
                      options.height, u0, u1, v0, v1))
      continue;
    u0 = std::max(u0, region.u0);
    u1 = std::min(u1, region.u1);
    v0 = std::max(v0, region.v0);
    v1 = std::min(v1, region.v1);
    if (u0 > u1 || v0 > v1) continue;
    tracePrimitive(scene.primitives[pi], static_cast<std::int32_t>(pi), view.rays, u0, u1, v0, v1,
                   region, zbuf.data(), hit.data());
  }
}

// A thread's buffers, kept from frame to frame (every frame writes them whole before it
// reads them): a 640x480 frame would otherwise map and zero 3 MB of fresh pages each time.
struct Scratch {
  std::vector<float> zbuf;
  std::vector<std::int32_t> hit;
  std::vector<std::uint8_t> shadow;
};

Scratch& threadScratch() {
  thread_local Scratch scratch;
  return scratch;
}

}  // namespace

RenderedFrame render(const SynthScene& scene, const CameraPose& pose, const RenderOptions& options,
                     std::uint64_t noise_seed) {
  validate(options);
  const int W = options.width, H = options.height;
  const std::size_t N = static_cast<std::size_t>(W) * H;
  const CameraIntrinsics& K = options.intrinsics;
  const View view = viewOf(scene, pose, options);

  Scratch& scratch = threadScratch();
  traceRegion(scene, view, options, Region{0, W - 1, 0, H - 1}, scratch.zbuf, scratch.hit);
  projectorShadows(scratch.zbuf, K, options.noise, W, H, scratch.shadow);

  RenderedFrame out;
  RgbdFrame& frame = out.labeled.frame;
  frame.width = W;
  frame.height = H;
  frame.intrinsics = K;
  frame.extrinsics = extrinsicsOf(pose);
  frame.source = "synth seed " + std::to_string(scene.seed);
  frame.depth_mm.assign(N, 0);
  frame.rgb.resize(N);
  out.labeled.labels.resize(N);
  out.true_depth_m.resize(N);
  out.object.resize(N);
  shadePixels(scene, view.rays, scratch.zbuf, scratch.hit, scratch.shadow, options, view.X, view.Y,
              view.Hc, noise_seed, out);
  return out;
}

int countObjectPixels(const SynthScene& scene, const CameraPose& pose,
                      const RenderOptions& options, int object) {
  validate(options);
  if (object < 0 || static_cast<std::size_t>(object) >= scene.objects.size())
    throw Error("synth: countObjectPixels: object " + std::to_string(object) +
                " is not in the scene (" + std::to_string(scene.objects.size()) + " objects)");
  const View view = viewOf(scene, pose, options);
  const int W = options.width, H = options.height;
  // Only the pixels one of the object's primitives is traced on can show it: the union of
  // their screen bounding boxes (the whole image for the shell's surfaces, objects 0..5).
  Region region{W, -1, H, -1};
  auto add = [&region](int u0, int u1, int v0, int v1) {
    region.u0 = std::min(region.u0, u0);
    region.u1 = std::max(region.u1, u1);
    region.v0 = std::min(region.v0, v0);
    region.v1 = std::max(region.v1, v1);
  };
  if (object < 6) add(0, W - 1, 0, H - 1);
  for (const Primitive& p : scene.primitives) {
    int u0, u1, v0, v1;
    if (p.object == object &&
        screenBounds(p, view.world_to_cam, options.intrinsics, W, H, u0, u1, v0, v1))
      add(u0, u1, v0, v1);
  }
  if (region.u0 > region.u1 || region.v0 > region.v1) return 0;
  Scratch& scratch = threadScratch();
  traceRegion(scene, view, options, region, scratch.zbuf, scratch.hit);
  int count = 0;
  for (std::size_t i = 0; i < region.pixels(); ++i) {
    const std::int32_t h = scratch.hit[i];
    count += (h < 0 ? -1 - h : scene.primitives[static_cast<std::size_t>(h)].object) == object;
  }
  return count;
}

}  // namespace findmug::synth
