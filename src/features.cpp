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
#include "findmug/features.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "findmug/error.hpp"
#include "scratch.hpp"

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
  std::array<float, 256> linear_{};
  std::array<float, kSteps + 1> f_{};
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
    const float len2 = n.squaredNorm();
    if (!(len2 > 0.0f) || !std::isfinite(len2)) return;
    const float inv = 1.0f / std::sqrt(len2);
    const float ux = n.x() * inv, uy = n.y() * inv, uz = n.z() * inv;
    ++normal_count;
    nx += ux, ny += uy, nz += uz;
    // θ = angle to +z: cos θ = uz, sin θ = |horizontal part| >= 0.
    cos_sum += uz;
    sin_sum += std::sqrt(ux * ux + uy * uy);
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

  // One sequential pass over the image. Pixels come in horizontal runs of
  // the same segment (a run goes on across pixels without a valid point or
  // a segment); each run is summed in local variables and merged into its
  // segment's accumulator once. The run's accumulator is a local whose
  // address never escapes (no lambda captures it), so the compiler keeps its
  // sums in registers; captured by a lambda, its 24 sums stayed in memory
  // with a load and a store each per pixel, which made this pass
  // store-bound. The run uses the segment's reference point, so merging is
  // plain addition.
  const int* pixel_segment = segmentation.pixel_segment.data();
  const Eigen::Vector3f* points = cloud_ground.points.data();
  const Eigen::Vector3f* normals = normals_ground.normals.data();
  const Rgb8* colors = cloud_ground.colors.data();
  std::size_t i = 0;
  while (i < pixels) {
    const int s = pixel_segment[i];
    if (s < 0 || !std::isfinite(points[i].z())) {
      ++i;
      continue;
    }
    if (static_cast<std::size_t>(s) >= segment_count) {
      throw Error("computeFeatures: pixel " + std::to_string(i) + " belongs to segment " +
                  std::to_string(s) + " but there are only " + std::to_string(segment_count));
    }
    PatchAccumulator& target = acc[static_cast<std::size_t>(s)];
    if (target.count == 0) target.ref = points[i];
    PatchAccumulator run;  // never leaves this scope: its sums stay in registers
    run.ref = target.ref;
    run.ref_fixed = true;
    for (; i < pixels; ++i) {
      const int t = pixel_segment[i];
      if (t < 0) continue;
      const Eigen::Vector3f& p = points[i];
      if (!std::isfinite(p.z())) continue;
      if (t != s) break;
      run.addPoint(p);
      run.addNormal(normals[i]);
      run.addLab(lab(colors[i]));
    }
    target.merge(run);
  }

  out.features.resize(segment_count);
  out.centroids.resize(segment_count);
  out.moments.resize(segment_count);
  out.regions.clear();
  out.scene.clear();
  for (std::size_t s = 0; s < segment_count; ++s) {
    if (acc[s].count == 0) {
      throw Error("computeFeatures: segment " + std::to_string(s) + " (" +
                  std::to_string(segmentation.segments[s].size()) + " pixels) has no valid point");
    }
    out.features[s] = acc[s].finish(&out.centroids[s], &out.moments[s]);
  }
}

}  // namespace findmug
