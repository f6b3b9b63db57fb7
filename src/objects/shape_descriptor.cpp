// The taught objects' global shape descriptor (object_model.hpp): PCL's
// Ensemble of Shape Functions (ESF, Wohlkinger & Vincze 2011), made
// deterministic.
//
// Why the preprocessor below: pcl::ESFEstimation (PCL 1.13, esf.hpp) draws its
// 20000 point triples with the C library's rand() after srand(time(nullptr))
// on every call. The same points then give a different descriptor each second,
// a match near the threshold flips from run to run, and the process's global
// rand() state is reseeded under anyone else who uses it. So this one file
// compiles PCL's ESF template itself (PCL_NO_PRECOMPILE, for a point type of
// its own so that no instantiation from libpcl_features can be picked instead)
// with srand/rand/time mapped to a per-thread generator reseeded to a fixed
// value at each call: the same points give the same bits, on any thread.
// Everything else is PCL's code as shipped.
#define PCL_NO_PRECOMPILE
#include <pcl/common/distances.h>
#include <pcl/common/transforms.h>
#include <pcl/features/feature.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>
#include <pcl/search/kdtree.h>
#include <pcl/search/organized.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/objects/object_model.hpp"

namespace findmug::detail {
// Only this file's ESF instantiation uses it (see above). Not in an unnamed
// namespace: PCL's point registration then leaves constants clang calls unused.
struct EIGEN_ALIGN16 EsfPoint {
  PCL_ADD_POINT4D;
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};
}  // namespace findmug::detail
POINT_CLOUD_REGISTER_POINT_STRUCT(findmug::detail::EsfPoint,
                                  (float, x, x)(float, y, y)(float, z, z))

namespace findmug::detail {
// ESF draws three indices a sample and draws again after a degenerate triple;
// on points that nearly all coincide once scaled to the unit sphere (a far
// outlier beside a tight clump: found by fuzzing a model file) almost every
// triple is degenerate and the loop would run for minutes. A sane cloud needs
// about 70,000 draws for ESF's 20,000 samples; past this many the draws stop
// (0.3 s under ASan, within the fuzzers' 1 s per input).
inline constexpr std::uint64_t kMaxEsfDraws = 400'000;
struct EsfDrawsExhausted {};

// splitmix64 (Steele, Lea & Flood 2014): one multiply-xorshift chain per draw.
inline thread_local std::uint64_t esf_random_state = 0;
inline thread_local std::uint64_t esf_draws = 0;
inline void esfSeed(unsigned /*ignored: PCL passes the time*/) {
  esf_random_state = 0x853C49E6748FEA9Bull;
  esf_draws = 0;
}
inline int esfRandom() {
  if (++esf_draws > kMaxEsfDraws) throw EsfDrawsExhausted{};
  std::uint64_t z = (esf_random_state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<int>(z >> 33);  // 0..2^31-1, as glibc's rand()
}
}  // namespace findmug::detail

// clang-format off
#define srand(seed) ::findmug::detail::esfSeed(seed)
#define rand() ::findmug::detail::esfRandom()
#define time(arg) 0u
#include <pcl/features/esf.h>
#include <pcl/features/impl/esf.hpp>
#undef time
#undef rand
#undef srand
// clang-format on

namespace findmug {
namespace {

// Runs PCL's ESF steps on a cloud directly: compute() would build a kd-tree
// of the cloud that ESF never uses.
class DeterministicEsf : public pcl::ESFEstimation<detail::EsfPoint, pcl::ESFSignature640> {
 public:
  void computeOn(const pcl::PointCloud<detail::EsfPoint>::ConstPtr& cloud,
                 pcl::PointCloud<pcl::ESFSignature640>& out) {
    setInputCloud(cloud);
    surface_ = cloud;
    computeFeature(out);
  }
};

// ESF's sampling loop draws again after a degenerate triple (two equal
// indices, a triangle of almost no area): on points along one line or all in
// one place it would never end. Refuse those before calling it.
void checkSpansSurface(const std::vector<Eigen::Vector3f>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p.cast<double>();
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d d = p.cast<double>() - mean;
    cov += d * d.transpose();
  }
  cov /= static_cast<double>(points.size());
  const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
  // Second-largest spread at least 2 mm (standard deviation) and 1 % of the largest.
  if (!(ev(1) >= 4e-6 && ev(1) >= 1e-4 * ev(2))) {
    throw Error("object shape: the " + std::to_string(points.size()) +
                " points do not span a surface (spreads " + std::to_string(std::sqrt(ev(2))) +
                " m and " + std::to_string(std::sqrt(std::max(0.0, ev(1)))) + " m)");
  }
}

// An object's points are metres from the robot: a coordinate beyond this can only come
// from a corrupt file or message, and would overflow ESF's squared distances (its voxel
// indices then come from NaN).
constexpr float kMaxPointCoordinate = 1000.0f;

void checkWithinReach(const std::vector<Eigen::Vector3f>& points) {
  for (const auto& p : points) {
    if (p.cwiseAbs().maxCoeff() > kMaxPointCoordinate) {
      throw Error("object shape: a point at (" + std::to_string(p.x()) + ", " +
                  std::to_string(p.y()) + ", " + std::to_string(p.z()) + ") is more than " +
                  std::to_string(static_cast<int>(kMaxPointCoordinate)) + " m away");
    }
  }
}

// The finite points, each place once, in their first occurrence's order (the
// pixel order the subsample spreads over). Repeated points only make ESF draw
// again (a triple needs three places): many copies of one point would keep it
// drawing for hours.
std::vector<Eigen::Vector3f> distinctFinitePoints(const std::vector<Eigen::Vector3f>& points) {
  std::vector<std::size_t> order;
  order.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    if (points[i].allFinite()) order.push_back(i);
  auto less = [&](std::size_t a, std::size_t b) {
    return std::lexicographical_compare(points[a].data(), points[a].data() + 3, points[b].data(),
                                        points[b].data() + 3);
  };
  std::stable_sort(order.begin(), order.end(), less);
  std::vector<char> keep(points.size(), 0);
  for (std::size_t k = 0; k < order.size(); ++k)
    keep[order[k]] = k == 0 || points[order[k]] != points[order[k - 1]];
  std::vector<Eigen::Vector3f> out;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (keep[i]) out.push_back(points[i]);
  return out;
}

}  // namespace

ObjectShapeDescriptor objectShapeDescriptor(const std::vector<Eigen::Vector3f>& points,
                                            int max_points) {
  std::vector<Eigen::Vector3f> finite = distinctFinitePoints(points);
  // Evenly over the (pixel-ordered) points, as objectPointsOf: ESF's cost
  // grows with the points it voxelises and looks up.
  const std::size_t n = finite.size();
  const std::size_t m = std::min(n, static_cast<std::size_t>(std::max(max_points, 1)));
  for (std::size_t k = 0; k < m; ++k) finite[k] = finite[k * n / m];
  finite.resize(m);
  if (static_cast<int>(finite.size()) < kMinObjectViewPoints) {
    throw Error("object shape: " + std::to_string(finite.size()) +
                " distinct finite points, need " + std::to_string(kMinObjectViewPoints));
  }
  checkWithinReach(finite);
  checkSpansSurface(finite);
  auto cloud = pcl::make_shared<pcl::PointCloud<detail::EsfPoint>>();
  cloud->resize(finite.size());
  for (std::size_t i = 0; i < finite.size(); ++i) {
    (*cloud)[i].x = finite[i].x();
    (*cloud)[i].y = finite[i].y();
    (*cloud)[i].z = finite[i].z();
  }
  // The estimator's 64^3 voxel table is 262144 ints in 4096 vectors: made
  // once per thread, cleared by ESF itself after each use.
  thread_local DeterministicEsf esf;
  pcl::PointCloud<pcl::ESFSignature640> out;
  try {
    esf.computeOn(cloud, out);
  } catch (const detail::EsfDrawsExhausted&) {
    throw Error("object shape: the points make no shape (nearly every triple of them is "
                "degenerate, e.g. a clump and a far outlier)");
  }
  ObjectShapeDescriptor d{};
  double sum = 0.0;
  for (int i = 0; i < kObjectShapeBins; ++i) {
    const float v = out[0].histogram[i];
    d[i] = std::isfinite(v) && v > 0.0f ? v : 0.0f;
    sum += d[i];
  }
  if (!(sum > 0.0)) throw Error("object shape: ESF gave an empty histogram");
  for (auto& v : d) v = static_cast<float>(v / sum);
  return d;
}

float shapeDescriptorDistance(const ObjectShapeDescriptor& a, const ObjectShapeDescriptor& b) {
  double l1 = 0.0;
  for (int i = 0; i < kObjectShapeBins; ++i) l1 += std::abs(static_cast<double>(a[i]) - b[i]);
  return static_cast<float>(std::clamp(0.5 * l1, 0.0, 1.0));
}

}  // namespace findmug
