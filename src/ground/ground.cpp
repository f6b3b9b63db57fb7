// ground.cpp — the ground plane from the camera mount, from floor labels, or
// estimated from the frame alone, and the ground-aligned frame built on it.
//
// Conventions (see ground.hpp): a plane is n.dot(p) + d = 0 in the camera
// optical frame with n unit and pointing up, so for any point p its height
// above the floor is n.dot(p) + d and the camera (p = 0) is d above it.
#include "findmug/ground/ground.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "common/cpu_features.hpp"
#include "common/simd_vec3.hpp"
#include "findmug/common/error.hpp"
#include "ground/ground_internal.hpp"

namespace findmug {

using detail::cosDeg;
using detail::kSameLevelM;
using detail::Plane;
using detail::quantile;
using detail::refitPlane;
using detail::validateConfig;

namespace {

constexpr std::uint8_t kFloorId = static_cast<std::uint8_t>(Label::Floor);
// At most this many points score a RANSAC hypothesis; the final refit and the
// reported support use all of them. Keeps RANSAC cost independent of image size.
constexpr std::size_t kScoringSubset = 3000;
// estimateGround works on at most this many candidate points (evenly strided).
constexpr std::size_t kMaxCandidates = 20000;
// estimateGround extracts up to this many horizontal planes (floor, table
// tops, seats, shelves) before choosing the lowest.
constexpr int kMaxPlanes = 5;
// Horizontal planes of one scene agree on "up" within this angle (NYU depth
// bends large planes and furniture tops by up to ~9 degrees; the sloped
// surfaces seen on NYU frames, bed covers and cushions, are off by 15+).
constexpr float kConsensusDeg = 12.0f;

// Whether this CPU runs the AVX2 variants below.
bool cpuAvx2() {
#if defined(FINDMUG_AVX2_DISPATCH)
  return detail::cpuHasAvx2();
#else
  return false;
#endif
}

// Plane through three points; false when they are (nearly) collinear.
bool planeThrough(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c,
                  Plane& plane) {
  Eigen::Vector3f n = (b - a).cross(c - a);
  const float norm = n.norm();
  if (!(norm > 1e-9f)) return false;
  plane.normal = n / norm;
  plane.offset = -plane.normal.dot(a);
  return true;
}

// Plane support: a point within `tol` of the plane and, when `normals` is
// given, with a normal within acos(cos_agree) of the plane's.
struct Support {
  const std::vector<Eigen::Vector3f>& points;
  const std::vector<Eigen::Vector3f>* normals = nullptr;
  float tol = 0.0f;
  float cos_agree = -1.0f;
  bool operator()(const Plane& p, std::size_t i) const {
    return std::abs(p.distance(points[i])) < tol &&
           (!normals || (*normals)[i].dot(p.normal) >= cos_agree);
  }
};

// The RANSAC scoring subset copied out of the image into contiguous arrays:
// scoring a hypothesis then streams through a few kB instead of gathering
// two 12-byte vectors per point from all over a 7 MB image (that gather was
// most of estimateGround's time). The arithmetic is Support's, in the same
// order, so the counts are the same.
class PackedSupport {
 public:
  void gather(const Support& support, const std::vector<std::size_t>& idx) {
    const std::size_t n = idx.size();
    const bool with_normals = support.normals != nullptr;
    px_.resize(n);
    py_.resize(n);
    pz_.resize(n);
    nx_.resize(with_normals ? n : 0);
    ny_.resize(with_normals ? n : 0);
    nz_.resize(with_normals ? n : 0);
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector3f& p = support.points[idx[k]];
      px_[k] = p.x();
      py_[k] = p.y();
      pz_[k] = p.z();
      if (with_normals) {
        const Eigen::Vector3f& q = (*support.normals)[idx[k]];
        nx_[k] = q.x();
        ny_[k] = q.y();
        nz_[k] = q.z();
      }
    }
    tol_ = support.tol;
    cos_agree_ = support.cos_agree;
    with_normals_ = with_normals;
  }
  std::size_t count(const Plane& p, bool avx2) const {
#if defined(FINDMUG_AVX2_DISPATCH)
    if (avx2) return countAvx2(p);
#endif
    (void)avx2;
    return countPortable(p, 0, 0);
  }

 private:
  // Points [begin, size) counted one by one, added to `score`.
  std::size_t countPortable(const Plane& p, std::size_t begin, std::size_t score) const {
    const float a = p.normal.x(), b = p.normal.y(), c = p.normal.z(), d = p.offset;
    const std::size_t n = px_.size();
    if (with_normals_) {
      for (std::size_t k = begin; k < n; ++k) {
        const bool near = std::abs(a * px_[k] + b * py_[k] + c * pz_[k] + d) < tol_;
        const bool agree = nx_[k] * a + ny_[k] * b + nz_[k] * c >= cos_agree_;
        score += (near && agree) ? 1 : 0;
      }
    } else {
      for (std::size_t k = begin; k < n; ++k)
        score += std::abs(a * px_[k] + b * py_[k] + c * pz_[k] + d) < tol_ ? 1 : 0;
    }
    return score;
  }

#if defined(FINDMUG_AVX2_DISPATCH)
  // Eight points per step, the same IEEE operations in the same order as
  // countPortable (no FMA; the ordered comparisons are false for NaN as `<`
  // and `>=` are), counted in 32-bit lanes (n <= kScoringSubset): the same
  // count. RANSAC scores 200 hypotheses per plane, up to five planes a frame.
  __attribute__((target("avx2"))) std::size_t countAvx2(const Plane& p) const {
    const __m256 a = _mm256_set1_ps(p.normal.x()), b = _mm256_set1_ps(p.normal.y());
    const __m256 c = _mm256_set1_ps(p.normal.z()), d = _mm256_set1_ps(p.offset);
    const __m256 tol = _mm256_set1_ps(tol_), cos_agree = _mm256_set1_ps(cos_agree_);
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    const std::size_t n = px_.size();
    __m256i counts = _mm256_setzero_si256();
    std::size_t k = 0;
    for (; k + 8 <= n; k += 8) {
      const __m256 x = _mm256_loadu_ps(px_.data() + k);
      const __m256 y = _mm256_loadu_ps(py_.data() + k);
      const __m256 z = _mm256_loadu_ps(pz_.data() + k);
      const __m256 dist =
          _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a, x), _mm256_mul_ps(b, y)),
                                      _mm256_mul_ps(c, z)),
                        d);
      __m256 hit = _mm256_cmp_ps(_mm256_and_ps(dist, abs_mask), tol, _CMP_LT_OQ);
      if (with_normals_) {
        const __m256 nx = _mm256_loadu_ps(nx_.data() + k);
        const __m256 ny = _mm256_loadu_ps(ny_.data() + k);
        const __m256 nz = _mm256_loadu_ps(nz_.data() + k);
        const __m256 dot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, a), _mm256_mul_ps(ny, b)),
                                         _mm256_mul_ps(nz, c));
        hit = _mm256_and_ps(hit, _mm256_cmp_ps(dot, cos_agree, _CMP_GE_OQ));
      }
      counts = _mm256_sub_epi32(counts, _mm256_castps_si256(hit));  // a hit is -1
    }
    alignas(32) std::uint32_t lanes[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), counts);
    std::size_t score = 0;
    for (std::uint32_t lane : lanes) score += lane;
    return countPortable(p, k, score);
  }
#endif

  std::vector<float> px_, py_, pz_, nx_, ny_, nz_;
  float tol_ = 0.0f, cos_agree_ = -1.0f;
  bool with_normals_ = false;
};

// The indices among `idx` whose points support `plane`, in order, into `out`.
// Written without a branch per point: along the borders of planes, and in
// the candidates of several planes interleaved, the test is a coin flip that
// a branch would mispredict.
void selectSupport(const Support& support, const Plane& plane, const std::vector<std::size_t>& idx,
                   std::vector<std::size_t>& out) {
  out.resize(idx.size());
  std::size_t n = 0;
  for (std::size_t i : idx) {
    out[n] = i;
    n += support(plane, i) ? 1 : 0;
  }
  out.resize(n);
}

// selectSupport's loop for the indices from .. count-1 of support.points,
// appended to out[0 .. n) (out holds at least count entries); returns the
// new n.
std::size_t appendSupport(const Support& support, const Plane& plane, std::size_t from,
                          std::size_t count, std::vector<std::size_t>& out, std::size_t n) {
  for (std::size_t k = from; k < count; ++k) {
    out[n] = k;
    n += support(plane, k) ? 1 : 0;
  }
  return n;
}

#if defined(FINDMUG_AVX2_DISPATCH)
// The first block of eight normals [k, k + 8), k = begin, begin + 8, ...
// below end8, in which at least one has a finite x and n.dot(up) >=
// cos_tilt (Eigen's dot, no FMA); end8 when there is none.
__attribute__((target("avx2"))) std::size_t nextUpwardBlockAvx2(const Eigen::Vector3f* normals,
                                                                std::size_t begin, std::size_t end8,
                                                                const Eigen::Vector3f& up,
                                                                float cos_tilt) {
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 infinity = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 ux = _mm256_set1_ps(up.x()), uy = _mm256_set1_ps(up.y()),
               uz = _mm256_set1_ps(up.z());
  const __m256 limit = _mm256_set1_ps(cos_tilt);
  for (std::size_t k = begin; k < end8; k += 8) {
    __m256 x, y, z;
    detail::loadVec3x8(normals[k].data(), x, y, z);
    const __m256 finite = _mm256_cmp_ps(_mm256_and_ps(x, abs_mask), infinity, _CMP_LT_OQ);
    const __m256 dot = detail::dot3x8(x, y, z, ux, uy, uz);
    const __m256 pass = _mm256_and_ps(finite, _mm256_cmp_ps(dot, limit, _CMP_GE_OQ));
    if (_mm256_movemask_ps(pass) != 0) return k;
  }
  return end8;
}

// selectSupport over every index 0 .. count-1, eight points at a time: the
// same IEEE operations as Support (Eigen's dot of three is x + (y + z); no
// FMA), so the same indices.
__attribute__((target("avx2"))) void selectSupportAllAvx2(const Support& support,
                                                          const Plane& plane, std::size_t count,
                                                          std::vector<std::size_t>& out) {
  const float* points = support.points.front().data();
  const float* normals = support.normals->front().data();
  const __m256 a = _mm256_set1_ps(plane.normal.x()), b = _mm256_set1_ps(plane.normal.y());
  const __m256 c = _mm256_set1_ps(plane.normal.z()), d = _mm256_set1_ps(plane.offset);
  const __m256 tol = _mm256_set1_ps(support.tol), cos_agree = _mm256_set1_ps(support.cos_agree);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  out.resize(count);
  std::size_t n = 0, k = 0;
  for (; k + 8 <= count; k += 8) {
    __m256 x, y, z, nx, ny, nz;
    detail::loadVec3x8(points + 3 * k, x, y, z);
    detail::loadVec3x8(normals + 3 * k, nx, ny, nz);
    const __m256 dist = _mm256_add_ps(detail::dot3x8(a, b, c, x, y, z), d);
    const __m256 dot = detail::dot3x8(nx, ny, nz, a, b, c);
    const __m256 hit = _mm256_and_ps(_mm256_cmp_ps(_mm256_and_ps(dist, abs_mask), tol, _CMP_LT_OQ),
                                     _mm256_cmp_ps(dot, cos_agree, _CMP_GE_OQ));
    const unsigned bits = static_cast<unsigned>(_mm256_movemask_ps(hit));
    for (unsigned j = 0; j < 8; ++j) {
      out[n] = k + j;
      n += (bits >> j) & 1u;
    }
  }
  out.resize(appendSupport(support, plane, k, count, out, n));
}
#endif

// Calls visit(i), in order, for every i of each block of eight normals among
// the first `count` where at least one passes estimateGround's candidate
// test (finite x, n.dot(up) >= cos_tilt; Eigen's dot, no FMA); blocks
// where none does are skipped. Returns where the blocks ended (a multiple
// of eight); the caller visits the rest.
template <typename Visit>
std::size_t upwardNormalBlocks(const Eigen::Vector3f* normals, std::size_t count,
                               const Eigen::Vector3f& up, float cos_tilt, Visit&& visit) {
#if defined(FINDMUG_AVX2_DISPATCH)
  const std::size_t end8 = count / 8 * 8;
  for (std::size_t k = nextUpwardBlockAvx2(normals, 0, end8, up, cos_tilt); k < end8;
       k = nextUpwardBlockAvx2(normals, k + 8, end8, up, cos_tilt)) {
    for (std::size_t j = k; j < k + 8; ++j) visit(j);
  }
  return end8;
#else
  (void)normals, (void)count, (void)up, (void)cos_tilt, (void)visit;
  return 0;
#endif
}

// selectSupport over every index 0 .. count-1 of support.points (with normals).
void selectSupportAll(const Support& support, const Plane& plane, std::size_t count, bool avx2,
                      std::vector<std::size_t>& out) {
#if defined(FINDMUG_AVX2_DISPATCH)
  if (avx2 && count > 0) {
    selectSupportAllAvx2(support, plane, count, out);
    return;
  }
#endif
  (void)avx2;
  out.resize(count);
  out.resize(appendSupport(support, plane, 0, count, out, 0));
}

// Generic RANSAC + least-squares refinement over `points[idx]`. `accept`
// vets a hypothesis (and may reorient it), `inlier` decides support.
// Returns false when no hypothesis was accepted.
template <typename Accept>
bool ransacPlane(const std::vector<Eigen::Vector3f>& points, const std::vector<std::size_t>& idx,
                 int iterations, std::mt19937_64& rng, Accept accept, const Support& inlier,
                 bool avx2, Plane& result, std::vector<std::size_t>& inliers) {
  if (idx.size() < 3) return false;
  // Score on a fixed random subset so cost does not grow with the image.
  // Per-thread buffers: no allocation per call once warm.
  thread_local std::vector<std::size_t> scoring;
  thread_local PackedSupport packed;
  scoring.clear();
  if (idx.size() <= kScoringSubset) {
    scoring.assign(idx.begin(), idx.end());
  } else {
    scoring.reserve(kScoringSubset);
    std::sample(idx.begin(), idx.end(), std::back_inserter(scoring), kScoringSubset, rng);
  }
  packed.gather(inlier, scoring);
  std::uniform_int_distribution<std::size_t> pick(0, idx.size() - 1);
  Plane best;
  std::size_t best_score = 0;
  for (int it = 0; it < iterations; ++it) {
    Plane hyp;
    // Drawn one by one, last first: inside one call's arguments the draws would come in an
    // unspecified order (g++ right to left, clang left to right); this keeps g++'s planes.
    const std::size_t third = idx[pick(rng)];
    const std::size_t second = idx[pick(rng)];
    const std::size_t first = idx[pick(rng)];
    if (!planeThrough(points[first], points[second], points[third], hyp) || !accept(hyp)) {
      continue;
    }
    const std::size_t score = packed.count(hyp, avx2);
    if (score > best_score) {
      best_score = score;
      best = hyp;
    }
  }
  if (best_score < 3) return false;

  // Two rounds of refit-on-inliers: the first removes the bias of the
  // three-point sample, the second settles the inlier set.
  Plane plane = best;
  for (int round = 0; round < 2; ++round) {
    selectSupport(inlier, plane, idx, inliers);
    if (inliers.size() < 3) return false;
    plane = refitPlane(points, inliers, plane);
  }
  selectSupport(inlier, plane, idx, inliers);
  result = plane;
  return inliers.size() >= 3;
}

}  // namespace

namespace detail {

void validateConfig(const GroundConfig& config, const char* where) {
  auto bad = [&](const std::string& field, double value) {
    std::ostringstream msg;
    msg << where << ": invalid ground." << field << " = " << value;
    throw Error(msg.str());
  };
  if (!(config.ransac_inlier_m > 0.0f) || !std::isfinite(config.ransac_inlier_m))
    bad("ransac_inlier_m", config.ransac_inlier_m);
  if (config.ransac_iterations < 1 || config.ransac_iterations > 1000000)
    bad("ransac_iterations", config.ransac_iterations);
  if (config.min_floor_points < 3) bad("min_floor_points", config.min_floor_points);
  if (!(config.max_tilt_deg > 0.0f && config.max_tilt_deg < 90.0f))
    bad("max_tilt_deg", config.max_tilt_deg);
  if (!(config.min_inlier_fraction > 0.0f && config.min_inlier_fraction <= 1.0f))
    bad("min_inlier_fraction", config.min_inlier_fraction);
  if (!(config.normal_agreement_deg > 0.0f && config.normal_agreement_deg < 90.0f))
    bad("normal_agreement_deg", config.normal_agreement_deg);
  if (!(config.min_camera_height_m >= 0.0f && config.min_camera_height_m < 10.0f))
    bad("min_camera_height_m", config.min_camera_height_m);
  if (!(config.floor_percentile >= 0.0f && config.floor_percentile <= 50.0f))
    bad("floor_percentile", config.floor_percentile);
  if (!(config.percentile_margin_m >= 0.0f && config.percentile_margin_m < 10.0f))
    bad("percentile_margin_m", config.percentile_margin_m);
  if (!(config.prior_camera_height_m > 0.0f && config.prior_camera_height_m < 10.0f))
    bad("prior_camera_height_m", config.prior_camera_height_m);
  if (!(config.gravity_refine_deg >= 0.0f && config.gravity_refine_deg < 90.0f))
    bad("gravity_refine_deg", config.gravity_refine_deg);
  if (config.reestimate_every_frames < 1)
    bad("reestimate_every_frames", config.reestimate_every_frames);
  if (!(config.reuse_min_support_fraction > 0.0f && config.reuse_min_support_fraction <= 1.0f))
    bad("reuse_min_support_fraction", config.reuse_min_support_fraction);
}

float cosDeg(float deg) { return std::cos(deg * static_cast<float>(M_PI) / 180.0f); }

// Least-squares plane (total least squares: centroid + smallest principal
// axis) through the selected points. Keeps the orientation of `hint`.
Plane refitPlane(const std::vector<Eigen::Vector3f>& points, const std::vector<std::size_t>& idx,
                 const Plane& hint) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i : idx) mean += points[i].cast<double>();
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (std::size_t i : idx) {
    const Eigen::Vector3d q = points[i].cast<double>() - mean;
    scatter.noalias() += q * q.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(scatter);
  Eigen::Vector3f normal = eig.eigenvectors().col(0).cast<float>().normalized();
  if (normal.dot(hint.normal) < 0.0f) normal = -normal;
  Plane plane;
  plane.normal = normal;
  plane.offset = -normal.dot(mean.cast<float>());
  return plane;
}

// Value at fraction q (0..1) of `values` (reorders them).
float quantile(std::vector<float>& values, double q) {
  const auto k = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * (values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}

}  // namespace detail

const char* groundMethodName(GroundMethod method) {
  switch (method) {
    case GroundMethod::Given:
      return "plane";
    case GroundMethod::Extrinsics:
      return "extrinsics";
    case GroundMethod::FloorLabels:
      return "floor_labels";
    case GroundMethod::Estimated:
      return "estimated";
    case GroundMethod::GravityFloorLabels:
      return "gravity+floor_labels";
    case GroundMethod::GravityLowestPlane:
      return "gravity+lowest_plane";
    case GroundMethod::GravityLowPercentile:
      return "gravity+low_percentile";
    case GroundMethod::GravityHeightPrior:
      return "gravity+height_prior";
  }
  return "?";
}

GroundPlane groundFromPlane(const Eigen::Vector3f& normal_camera, float offset, int support) {
  const float norm = normal_camera.norm();
  if (!std::isfinite(norm) || !(norm > 1e-6f) || !std::isfinite(offset)) {
    std::ostringstream msg;
    msg << "groundFromPlane: degenerate plane normal (" << normal_camera.transpose() << ") offset "
        << offset;
    throw Error(msg.str());
  }
  Eigen::Vector3f up = normal_camera / norm;
  float d = offset / norm;
  if (d < 0.0f) {  // make the camera side the positive side
    up = -up;
    d = -d;
  }
  // x: the viewing direction (optical z) projected on the floor. When the
  // camera looks straight down that projection vanishes; image "up" (-y) is
  // then the natural forward direction.
  Eigen::Vector3f forward = Eigen::Vector3f::UnitZ() - up * up.z();
  if (forward.norm() < 1e-4f) forward = -Eigen::Vector3f::UnitY() - up * (-up.y());
  forward.normalize();
  const Eigen::Vector3f left = up.cross(forward);

  GroundPlane ground;
  ground.normal_camera = up;
  ground.offset = d;
  ground.support_points = support;
  Eigen::Matrix3f rotation;  // rows: ground axes expressed in the camera frame
  rotation.row(0) = forward;
  rotation.row(1) = left;
  rotation.row(2) = up;
  ground.camera_to_ground.setIdentity();
  ground.camera_to_ground.linear() = rotation;
  // The camera centre lies on the ground z axis at height d.
  ground.camera_to_ground.translation() = Eigen::Vector3f(0.0f, 0.0f, d);
  return ground;
}

GroundPlane groundFromExtrinsics(const CameraExtrinsics& extrinsics) {
  if (!std::isfinite(extrinsics.height_m) || extrinsics.height_m <= 0.0 ||
      !std::isfinite(extrinsics.pitch_rad) || std::abs(extrinsics.pitch_rad) >= M_PI / 2 ||
      !std::isfinite(extrinsics.roll_rad) || std::abs(extrinsics.roll_rad) >= M_PI / 2) {
    std::ostringstream msg;
    msg << "groundFromExtrinsics: invalid camera mount height_m=" << extrinsics.height_m
        << " pitch_rad=" << extrinsics.pitch_rad << " roll_rad=" << extrinsics.roll_rad;
    throw Error(msg.str());
  }
  // Camera orientation in a level frame (x forward, y left, z up):
  //  - level camera: optical z = forward, x = -left (right), y = -up (down);
  //  - pitch θ > 0 tips the optical axis down: rotation about the level
  //    frame's y (left) axis by +θ, taking forward (1,0,0) to (cosθ,0,-sinθ);
  //  - roll φ > 0 turns the camera's image axes clockwise as seen looking
  //    along the optical axis: rotation about optical z by +φ, taking image
  //    right (x) towards image down (y).
  // So R_level_from_camera = Ry(θ) * R0 * Rz(φ).
  const float pitch = static_cast<float>(extrinsics.pitch_rad);
  const float roll = static_cast<float>(extrinsics.roll_rad);
  Eigen::Matrix3f r0;
  r0.col(0) = Eigen::Vector3f(0, -1, 0);
  r0.col(1) = Eigen::Vector3f(0, 0, -1);
  r0.col(2) = Eigen::Vector3f(1, 0, 0);
  const Eigen::Matrix3f level_from_camera =
      Eigen::AngleAxisf(pitch, Eigen::Vector3f::UnitY()).toRotationMatrix() * r0 *
      Eigen::AngleAxisf(roll, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  // Up in camera coordinates is the level z axis pulled back.
  const Eigen::Vector3f up_camera = level_from_camera.transpose() * Eigen::Vector3f::UnitZ();
  GroundPlane ground = groundFromPlane(up_camera, static_cast<float>(extrinsics.height_m), 0);
  ground.method = GroundMethod::Extrinsics;
  return ground;
}

std::optional<GroundPlane> fitGroundToLabels(const OrganizedCloud& cloud_camera,
                                             const std::vector<std::uint8_t>& labels,
                                             const GroundConfig& config) {
  validateConfig(config, "fitGroundToLabels");
  if (labels.size() != cloud_camera.points.size()) {
    throw Error("fitGroundToLabels: label image has " + std::to_string(labels.size()) +
                " pixels but the cloud has " + std::to_string(cloud_camera.points.size()));
  }
  std::vector<std::size_t> floor;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (labels[i] == kFloorId && cloud_camera.valid(i)) floor.push_back(i);
  if (floor.size() < static_cast<std::size_t>(config.min_floor_points)) return std::nullopt;

  std::mt19937_64 rng(config.seed);
  const float tol = config.ransac_inlier_m;
  const auto& pts = cloud_camera.points;
  Plane plane;
  std::vector<std::size_t> inliers;
  const bool found = ransacPlane(
      pts, floor, config.ransac_iterations, rng, [](Plane&) { return true; },
      Support{pts, nullptr, tol}, cpuAvx2(), plane, inliers);
  if (!found || static_cast<double>(inliers.size()) < config.min_inlier_fraction * floor.size()) {
    return std::nullopt;
  }
  // groundFromPlane orients the normal so that the camera is above the floor.
  GroundPlane ground =
      groundFromPlane(plane.normal, plane.offset, static_cast<int>(inliers.size()));
  ground.method = GroundMethod::FloorLabels;
  return ground;
}

std::optional<GroundPlane> confirmGround(const OrganizedCloud& cloud_camera,
                                         const NormalImage& normals_camera,
                                         const GroundPlane& previous, const GroundConfig& config) {
  validateConfig(config, "confirmGround");
  if (normals_camera.normals.size() != cloud_camera.points.size() ||
      normals_camera.width != cloud_camera.width) {
    throw Error("confirmGround: normal image has " + std::to_string(normals_camera.normals.size()) +
                " entries but the cloud has " + std::to_string(cloud_camera.points.size()) +
                " points");
  }
  constexpr int kStep = 4;  // every 4th pixel of every 4th row
  const Eigen::Vector3f camera_up(0.0f, -1.0f, 0.0f);
  const float cos_tilt = cosDeg(config.max_tilt_deg);
  const Plane plane{previous.normal_camera, previous.offset};
  const Support supports{cloud_camera.points, &normals_camera.normals, config.ransac_inlier_m,
                         cosDeg(config.normal_agreement_deg)};
  std::size_t count = 0;
  for (int v = 0; v < cloud_camera.height; v += kStep) {
    const std::size_t row = static_cast<std::size_t>(v) * cloud_camera.width;
    for (int u = 0; u < cloud_camera.width; u += kStep) {
      const std::size_t i = row + static_cast<std::size_t>(u);
      // NaN points and normals fail both comparisons.
      if (normals_camera.normals[i].dot(camera_up) >= cos_tilt && supports(plane, i)) ++count;
    }
  }
  const double support = static_cast<double>(count) * kStep * kStep;
  if (support < config.min_floor_points ||
      support < config.reuse_min_support_fraction * previous.support_points) {
    return std::nullopt;
  }
  GroundPlane kept = previous;
  kept.support_points = static_cast<int>(support);
  return kept;
}

std::optional<GroundPlane> estimateGround(const OrganizedCloud& cloud_camera,
                                          const NormalImage& normals_camera,
                                          const GroundConfig& config) {
  return detail::estimateGround(cloud_camera, normals_camera, config, detail::GroundSimd::Auto);
}

namespace {

// A horizontal plane that estimateGround's sequential RANSAC found.
struct FoundPlane {
  Plane plane;
  std::size_t support;
  Eigen::Vector3f centroid;  // of the supporting points, camera frame
};

// estimateGround's candidates: points whose own normal is roughly "up",
// copied out with their normals, in pixel order. Normals face the camera,
// so a floor or table top seen from above has n.dot(-y) > 0, while a
// ceiling (seen from below) does not qualify. Everything after works on
// the copies by position: the RANSAC and refit passes then stream through
// them instead of gathering from all over the image (same values in the
// same order, so the same planes).
void collectUpwardCandidates(const OrganizedCloud& cloud_camera, const NormalImage& normals_camera,
                             const Eigen::Vector3f& camera_up, float cos_tilt, bool avx2,
                             std::vector<Eigen::Vector3f>& candidate_points,
                             std::vector<Eigen::Vector3f>& candidate_normals) {
  const auto& pts = cloud_camera.points;
  const auto& nrm = normals_camera.normals;
  candidate_points.clear();
  candidate_normals.clear();
  // The normal test first: it rules out most pixels, whose points are then
  // never read (half the memory traffic of this pass). With AVX2 it tests
  // eight normals at a time and skips the blocks where none points up.
  const auto take = [&](std::size_t i) {
    const Eigen::Vector3f& n = nrm[i];
    if (std::isfinite(n.x()) && n.dot(camera_up) >= cos_tilt && cloud_camera.valid(i)) {
      candidate_points.push_back(pts[i]);
      candidate_normals.push_back(n);
    }
  };
  std::size_t first_unscanned = 0;
  if (avx2) {
    first_unscanned = upwardNormalBlocks(nrm.data(), nrm.size(), camera_up, cos_tilt, take);
  }
  for (std::size_t i = first_unscanned; i < pts.size(); ++i) take(i);
}

// Sequential RANSAC over the candidates at `remaining` (consumed): peels off
// the horizontal planes one by one, up to kMaxPlanes, and keeps (in
// `planes`) those with min_sampled supporting points below the camera.
void peelHorizontalPlanes(const std::vector<Eigen::Vector3f>& candidate_points,
                          const Support& supports, const Eigen::Vector3f& camera_up, float cos_tilt,
                          std::size_t min_sampled, const GroundConfig& config, bool avx2,
                          std::vector<std::size_t>& remaining, std::vector<std::size_t>& inliers,
                          std::vector<std::size_t>& rest, std::vector<FoundPlane>& planes) {
  auto accept = [&](Plane& p) {
    if (p.normal.dot(camera_up) < 0.0f) {
      p.normal = -p.normal;
      p.offset = -p.offset;
    }
    return p.normal.dot(camera_up) >= cos_tilt;
  };
  planes.clear();
  std::mt19937_64 rng(config.seed);
  for (int k = 0; k < kMaxPlanes && remaining.size() >= std::max<std::size_t>(min_sampled, 3);
       ++k) {
    Plane plane;
    if (!ransacPlane(candidate_points, remaining, config.ransac_iterations, rng, accept, supports,
                     avx2, plane, inliers)) {
      break;
    }
    if (inliers.size() >= min_sampled && plane.offset > 0.0f) {
      Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
      for (std::size_t i : inliers) centroid += candidate_points[i];
      planes.push_back({plane, inliers.size(), centroid / static_cast<float>(inliers.size())});
    }
    // Remove this plane's points (inliers is sorted: it follows `remaining`).
    rest.clear();
    std::set_difference(remaining.begin(), remaining.end(), inliers.begin(), inliers.end(),
                        std::back_inserter(rest));
    remaining.swap(rest);
  }
}

// The floor among the found planes (not empty). Gravity consensus: every
// real horizontal surface (floor, table tops, seats) shares one normal,
// while sloped surfaces that slipped under the tilt limit (bed covers,
// cushions, ramps) each have their own. The reference "up" is the plane
// whose direction gathers the most support over all planes; the others must
// agree with it. Then the lowest level of the consistent planes, and within
// that level the best-supported plane. "Low" is measured at the supporting
// points (their centroid's depth below the camera along the reference up),
// not by the plane offset: a slightly tilted plane's extension can pass far
// below the floor at the camera while its points sit well above it.
const FoundPlane& chooseFloorPlane(const std::vector<FoundPlane>& planes) {
  const float cos_consensus = cosDeg(kConsensusDeg);
  std::size_t best_consensus = 0;
  Eigen::Vector3f reference_up = planes.front().plane.normal;
  for (const auto& f : planes) {
    std::size_t consensus = 0;
    for (const auto& g : planes)
      if (f.plane.normal.dot(g.plane.normal) >= cos_consensus) consensus += g.support;
    if (consensus > best_consensus) {
      best_consensus = consensus;
      reference_up = f.plane.normal;
    }
  }
  auto depthBelowCamera = [&](const FoundPlane& f) { return -reference_up.dot(f.centroid); };
  auto consistent = [&](const FoundPlane& f) {
    return f.plane.normal.dot(reference_up) >= cos_consensus;
  };
  float lowest = -std::numeric_limits<float>::infinity();
  for (const auto& f : planes)
    if (consistent(f)) lowest = std::max(lowest, depthBelowCamera(f));
  const FoundPlane* chosen = nullptr;
  for (const auto& f : planes) {
    if (consistent(f) && lowest - depthBelowCamera(f) <= kSameLevelM &&
        (!chosen || f.support > chosen->support)) {
      chosen = &f;
    }
  }
  return *chosen;  // the reference plane itself is consistent
}

}  // namespace

std::optional<GroundPlane> detail::estimateGround(const OrganizedCloud& cloud_camera,
                                                  const NormalImage& normals_camera,
                                                  const GroundConfig& config, GroundSimd simd) {
  validateConfig(config, "estimateGround");
  const bool avx2 = simd == GroundSimd::Auto && cpuAvx2();
  if (normals_camera.normals.size() != cloud_camera.points.size()) {
    throw Error("estimateGround: normal image has " +
                std::to_string(normals_camera.normals.size()) + " entries but the cloud has " +
                std::to_string(cloud_camera.points.size()) + " points");
  }
  const Eigen::Vector3f camera_up(0.0f, -1.0f, 0.0f);
  const float cos_tilt = cosDeg(config.max_tilt_deg);
  const float cos_agree = cosDeg(config.normal_agreement_deg);
  const float tol = config.ransac_inlier_m;

  // Per-thread buffers: estimateGround runs once per frame, and a stream of
  // frames then reuses them instead of allocating.
  thread_local std::vector<Eigen::Vector3f> candidate_points_tls, candidate_normals_tls;
  thread_local std::vector<std::size_t> remaining_tls, rest_tls, inliers_tls;
  thread_local std::vector<FoundPlane> planes_tls;
  std::vector<Eigen::Vector3f>& candidate_points = candidate_points_tls;
  std::vector<Eigen::Vector3f>& candidate_normals = candidate_normals_tls;
  collectUpwardCandidates(cloud_camera, normals_camera, camera_up, cos_tilt, avx2, candidate_points,
                          candidate_normals);
  // RANSAC runs on at most kMaxCandidates of them, evenly strided.
  const std::size_t candidates = candidate_points.size();
  const std::size_t stride = candidates / kMaxCandidates + 1;
  std::vector<std::size_t>& remaining = remaining_tls;
  remaining.clear();
  for (std::size_t k = 0; k < candidates; k += stride) remaining.push_back(k);
  const auto min_sampled = static_cast<std::size_t>(config.min_floor_points) / stride;
  const Support supports{candidate_points, &candidate_normals, tol, cos_agree};
  std::vector<FoundPlane>& planes = planes_tls;
  std::vector<std::size_t>& inliers = inliers_tls;
  peelHorizontalPlanes(candidate_points, supports, camera_up, cos_tilt, min_sampled, config, avx2,
                       remaining, inliers, rest_tls, planes);
  if (planes.empty()) return std::nullopt;

  // Final least-squares fit on every candidate (not just the strided subset)
  // that supports the chosen plane, and the support at full resolution.
  Plane plane = chooseFloorPlane(planes).plane;
  for (int round = 0; round < 2; ++round) {
    selectSupportAll(supports, plane, candidates, avx2, inliers);
    if (inliers.size() < static_cast<std::size_t>(config.min_floor_points)) return std::nullopt;
    plane = refitPlane(candidate_points, inliers, plane);
  }
  if (plane.normal.dot(camera_up) < cos_tilt || plane.offset < config.min_camera_height_m) {
    return std::nullopt;
  }
  GroundPlane ground =
      groundFromPlane(plane.normal, plane.offset, static_cast<int>(inliers.size()));
  ground.method = GroundMethod::Estimated;
  return ground;
}

std::vector<std::size_t> detail::planeSupport(const std::vector<Eigen::Vector3f>& points,
                                              const std::vector<Eigen::Vector3f>& normals,
                                              const Eigen::Vector3f& plane_normal,
                                              float plane_offset, float tol, float cos_agree,
                                              GroundSimd simd) {
  if (normals.size() != points.size())
    throw Error("planeSupport: normals and points differ in size");
  const Support support{points, &normals, tol, cos_agree};
  std::vector<std::size_t> out;
  selectSupportAll(support, Plane{plane_normal, plane_offset}, points.size(),
                   simd == GroundSimd::Auto && cpuAvx2(), out);
  return out;
}

std::size_t detail::planeSupportCount(const std::vector<Eigen::Vector3f>& points,
                                      const std::vector<Eigen::Vector3f>& normals,
                                      const Eigen::Vector3f& plane_normal, float plane_offset,
                                      float tol, float cos_agree, GroundSimd simd) {
  if (normals.size() != points.size()) {
    throw Error("planeSupportCount: normals and points differ in size");
  }
  const Support support{points, &normals, tol, cos_agree};
  std::vector<std::size_t> idx(points.size());
  for (std::size_t k = 0; k < idx.size(); ++k) idx[k] = k;
  PackedSupport packed;
  packed.gather(support, idx);
  return packed.count(Plane{plane_normal, plane_offset}, simd == GroundSimd::Auto && cpuAvx2());
}

}  // namespace findmug
