// Region features: union-find over the patch adjacency graph, then one
// scatter matrix per region pooled from per-patch moments. The moments come
// from the 14-D features' pass (computeFeatures) or, standalone, from one pass
// over the pixels.
#include "findmug/features/region_features.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "findmug/common/error.hpp"
#include "features/moments_internal.hpp"
#include "common/scratch.hpp"
#include "common/union_find.hpp"

namespace findmug {

namespace {

// Regions and their features from per-segment moments (every count > 0).
void regionsFromMoments(const std::vector<SegmentMoments>& patch,
                        const Oversegmentation& segmentation, const RegionConfig& config,
                        RegionFeatures& out) {
  const std::size_t n = patch.size();
  // Working memory kept per thread between frames (scratch.hpp).
  thread_local std::vector<SegmentMoments> region_tls;
  thread_local std::vector<int> parent_tls, root_region_tls;
  thread_local std::vector<std::array<float, kRegionFeatureDim>> per_region_tls;
  detail::Borrowed region_buffer(region_tls);
  detail::Borrowed parent_buffer(parent_tls), root_region_buffer(root_region_tls);
  detail::Borrowed per_region_buffer(per_region_tls);

  // Merge neighbours that continue each other's surface.
  const double cos_limit = std::cos(static_cast<double>(config.normal_angle_deg) * M_PI / 180.0);
  const double max_offset = config.plane_distance_m;
  std::vector<int>& parent = *parent_buffer;
  parent.resize(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [a, b] : segmentation.edges) {
    if (a < 0 || b < 0 || static_cast<std::size_t>(a) >= n || static_cast<std::size_t>(b) >= n) {
      throw Error("computeRegionFeatures: edge (" + std::to_string(a) + ", " + std::to_string(b) +
                  ") names a segment outside 0.." + std::to_string(n - 1));
    }
    const SegmentMoments& pa = patch[static_cast<std::size_t>(a)];
    const SegmentMoments& pb = patch[static_cast<std::size_t>(b)];
    if (pa.normal_sum.squaredNorm() == 0 || pb.normal_sum.squaredNorm() == 0) continue;
    const Eigen::Vector3d na = pa.normal_sum.normalized();
    const Eigen::Vector3d nb = pb.normal_sum.normalized();
    if (na.dot(nb) < cos_limit) continue;
    const Eigen::Vector3d d = pb.mean - pa.mean;
    if (std::abs(na.dot(d)) > max_offset || std::abs(nb.dot(d)) > max_offset) continue;
    detail::unionFindJoin(parent, a, b);
  }

  out.segment_region.assign(n, -1);
  std::vector<int>& root_region = *root_region_buffer;
  root_region.assign(n, -1);
  std::vector<SegmentMoments>& region = *region_buffer;
  region.clear();
  for (std::size_t s = 0; s < n; ++s) {
    const int root = detail::unionFindRoot(parent, static_cast<int>(s));
    if (root_region[root] < 0) {
      root_region[root] = static_cast<int>(region.size());
      region.emplace_back();
    }
    out.segment_region[s] = root_region[root];
    detail::poolMoments(region[static_cast<std::size_t>(root_region[root])], patch[s]);
  }
  out.region_count = static_cast<int>(region.size());

  std::vector<std::array<float, kRegionFeatureDim>>& per_region = *per_region_buffer;
  per_region.resize(region.size());
  for (std::size_t r = 0; r < region.size(); ++r) {
    const SegmentMoments& m = region[r];
    const Eigen::Matrix3d covariance = m.scatter / m.count;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d ev = eig.eigenvalues().cwiseMax(0.0);  // ascending
    const double major = std::sqrt(12.0 * ev[2]);
    const double minor = std::sqrt(12.0 * ev[1]);
    double angle = M_PI / 2;  // no normals at all: call it vertical, the commonest case
    if (m.normal_sum.squaredNorm() > 0)
      angle = std::acos(std::clamp(m.normal_sum.normalized().z(), -1.0, 1.0));
    per_region[r] = {static_cast<float>(major * minor),
                     static_cast<float>(major),
                     static_cast<float>(minor),
                     static_cast<float>(m.mean.z()),
                     m.max_z,
                     static_cast<float>(angle)};
  }
  out.values.resize(n * kRegionFeatureDim);
  for (std::size_t s = 0; s < n; ++s) {
    const auto& v = per_region[static_cast<std::size_t>(out.segment_region[s])];
    std::copy(v.begin(), v.end(),
              out.values.begin() + static_cast<std::ptrdiff_t>(s * kRegionFeatureDim));
  }
}

}  // namespace

RegionFeatures computeRegionFeatures(const OrganizedCloud& cloud_ground,
                                     const NormalImage& normals_ground,
                                     const Oversegmentation& segmentation,
                                     const RegionConfig& config) {
  RegionFeatures out;
  computeRegionFeaturesInto(cloud_ground, normals_ground, segmentation, config, out);
  return out;
}

void computeRegionFeaturesInto(const OrganizedCloud& cloud_ground,
                               const NormalImage& normals_ground,
                               const Oversegmentation& segmentation, const RegionConfig& config,
                               RegionFeatures& out) {
  const std::size_t pixels = segmentation.pixel_segment.size();
  if (cloud_ground.points.size() != pixels || normals_ground.normals.size() != pixels) {
    throw Error("computeRegionFeatures: grids disagree: segmentation has " +
                std::to_string(pixels) + " pixels, cloud " +
                std::to_string(cloud_ground.points.size()) + ", normals " +
                std::to_string(normals_ground.normals.size()));
  }
  const std::size_t n = segmentation.segments.size();
  // Raw sums about a common reference point (the first valid point), so that
  // the second moments stay well conditioned; turned into means and
  // scatters below.
  Eigen::Vector3d ref = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < pixels; ++i) {
    if (segmentation.pixel_segment[i] >= 0 && cloud_ground.valid(i)) {
      ref = cloud_ground.points[i].cast<double>();
      break;
    }
  }
  thread_local std::vector<SegmentMoments> patch_tls;
  detail::Borrowed patch_buffer(patch_tls);
  std::vector<SegmentMoments>& patch = *patch_buffer;
  patch.assign(n, SegmentMoments{});
  for (SegmentMoments& m : patch) m.max_z = -std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < pixels; ++i) {
    const int s = segmentation.pixel_segment[i];
    if (s < 0 || !cloud_ground.valid(i)) continue;
    if (static_cast<std::size_t>(s) >= n) {
      throw Error("computeRegionFeatures: pixel " + std::to_string(i) + " belongs to segment " +
                  std::to_string(s) + " but there are only " + std::to_string(n));
    }
    SegmentMoments& m = patch[static_cast<std::size_t>(s)];
    const Eigen::Vector3d p = cloud_ground.points[i].cast<double>() - ref;
    m.count += 1;
    m.mean += p;                  // the sum until the end of the pass
    m.scatter += p * p.transpose();  // raw second moments until then
    m.max_z = std::max(m.max_z, cloud_ground.points[i].z());
    const Eigen::Vector3f& nrm = normals_ground.normals[i];
    if (nrm.allFinite()) m.normal_sum += nrm.cast<double>();
  }
  for (std::size_t s = 0; s < n; ++s) {
    SegmentMoments& m = patch[s];
    if (m.count == 0) {
      throw Error("computeRegionFeatures: segment " + std::to_string(s) + " (" +
                  std::to_string(segmentation.segments[s].size()) + " pixels) has no valid point");
    }
    const Eigen::Vector3d sum = m.mean;
    m.scatter -= sum * sum.transpose() / m.count;
    m.mean = ref + sum / m.count;
  }
  regionsFromMoments(patch, segmentation, config, out);
}

RegionFeatures computeRegionFeatures(const SegmentFeatures& features,
                                     const Oversegmentation& segmentation,
                                     const RegionConfig& config) {
  RegionFeatures out;
  computeRegionFeaturesInto(features, segmentation, config, out);
  return out;
}

void computeRegionFeaturesInto(const SegmentFeatures& features,
                               const Oversegmentation& segmentation, const RegionConfig& config,
                               RegionFeatures& out) {
  const std::size_t n = segmentation.segments.size();
  if (features.moments.size() != n) {
    throw Error("computeRegionFeatures: the segmentation has " + std::to_string(n) +
                " segments but the features carry moments of " +
                std::to_string(features.moments.size()) +
                " (computeFeatures of another segmentation?)");
  }
  for (std::size_t s = 0; s < n; ++s) {
    const SegmentMoments& m = features.moments[s];
    if (!(m.count > 0) || !m.mean.allFinite() || !m.scatter.allFinite() ||
        !m.normal_sum.allFinite()) {
      throw Error("computeRegionFeatures: segment " + std::to_string(s) + " has moments of " +
                  std::to_string(m.count) + " points, or non-finite ones");
    }
  }
  regionsFromMoments(features.moments, segmentation, config, out);
}

}  // namespace findmug
