// Object features: large planes from the coplanar regions, object candidates
// by union-find over convex or smooth joints, then per group the pooled
// moments, its largest up-facing part, what rises above that part, and the
// nearest wall.
#include "findmug/features/object_features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "features/moments_internal.hpp"
#include "common/scratch.hpp"
#include "common/union_find.hpp"
#include "findmug/common/error.hpp"

namespace findmug {

namespace {

using detail::unionFindJoin;
using detail::unionFindRoot;

// What the grouping needs of one patch.
struct Patch {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit, or zero without normals
  double radius = 0;  // half the diagonal of the rectangle with the patch's variances (m)
  bool up = false, down = false, vertical = false;
};

// The major axis on the ground of the 2-D (ground-plane) scatter of `m`
// (unit; x when the scatter is round or empty).
Eigen::Vector2d majorAxis(const SegmentMoments& m) {
  const double a = m.scatter(0, 0), b = m.scatter(0, 1), d = m.scatter(1, 1);
  if (b == 0) return a >= d ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1);
  const double mean = 0.5 * (a + d);
  const double major = mean + std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  return Eigen::Vector2d(b, major - a).normalized();
}

// A footprint box on the ground along fixed axes: the patches' extents along
// them, each patch as wide as a uniform strip of its variance (2 sqrt(3 var)),
// so that a table's legs at its corners do not widen it, as they widen the
// pooled variance.
struct FootprintBox {
  Eigen::Vector2d major_axis = Eigen::Vector2d(1, 0);
  double lo[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  double hi[2] = {-std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity()};

  explicit FootprintBox(const Eigen::Vector2d& axis) : major_axis(axis) {}
  void add(const SegmentMoments& m) {
    const Eigen::Vector2d axes[2] = {major_axis, Eigen::Vector2d(-major_axis.y(), major_axis.x())};
    const Eigen::Matrix2d covariance = m.scatter.topLeftCorner<2, 2>() / m.count;
    for (int k = 0; k < 2; ++k) {
      const double centre = axes[k].dot(m.mean.head<2>());
      const double half = std::sqrt(3.0 * std::max(axes[k].dot(covariance * axes[k]), 0.0));
      lo[k] = std::min(lo[k], centre - half);
      hi[k] = std::max(hi[k], centre + half);
    }
  }
  // Side lengths, the longer first (0, 0 when empty).
  std::pair<double, double> extents() const {
    const double a = std::max(hi[0] - lo[0], 0.0), b = std::max(hi[1] - lo[1], 0.0);
    return {std::max(a, b), std::min(a, b)};
  }
};

void checkInputs(const SegmentFeatures& features, const Oversegmentation& segmentation,
                 const RegionFeatures& regions) {
  const std::size_t n = segmentation.segments.size();
  if (features.features.size() != n || features.moments.size() != n) {
    throw Error("computeObjectFeatures: the segmentation has " + std::to_string(n) +
                " segments but the features describe " + std::to_string(features.features.size()) +
                " with moments of " + std::to_string(features.moments.size()) +
                " (computeFeatures of another segmentation?)");
  }
  if (regions.segment_region.size() != n || regions.values.size() != n * kRegionFeatureDim) {
    throw Error("computeObjectFeatures: the regions cover " +
                std::to_string(regions.segment_region.size()) + " segments, not " +
                std::to_string(n) + " (computeRegionFeatures of another segmentation?)");
  }
  for (std::size_t s = 0; s < n; ++s) {
    const SegmentMoments& m = features.moments[s];
    const FeatureVector& f = features.features[s];
    if (!(m.count > 0) || !m.mean.allFinite() || !m.scatter.allFinite() ||
        !m.normal_sum.allFinite() || !std::isfinite(f[4]) || !std::isfinite(f[5])) {
      throw Error("computeObjectFeatures: segment " + std::to_string(s) + " has moments of " +
                  std::to_string(m.count) + " points, or non-finite moments or heights");
    }
    const int r = regions.segment_region[s];
    if (r < 0 || r >= regions.region_count) {
      throw Error("computeObjectFeatures: segment " + std::to_string(s) + " is in region " +
                  std::to_string(r) + " of " + std::to_string(regions.region_count));
    }
  }
  for (const auto& [a, b] : segmentation.edges) {
    if (a < 0 || b < 0 || static_cast<std::size_t>(a) >= n || static_cast<std::size_t>(b) >= n) {
      throw Error("computeObjectFeatures: edge (" + std::to_string(a) + ", " + std::to_string(b) +
                  ") names a segment outside 0.." + std::to_string(n) + "-1");
    }
  }
}

// The kind of a coplanar region: floor, wall, ceiling or none of them (Object).
GroupKind regionKind(const float* value, const ObjectConfig& config, double tolerance) {
  const double area = value[0], height = value[3], angle = value[5];
  if (angle < tolerance && height < config.floor_height_m) return GroupKind::Floor;
  if (area >= config.plane_min_area_m2) {
    if (std::abs(angle - M_PI / 2) < tolerance) return GroupKind::Wall;
    if (angle > M_PI - tolerance) return GroupKind::Ceiling;
  }
  return GroupKind::Object;
}

// The patches' normals, radii and orientation.
void describePatches(const SegmentFeatures& features, double tolerance,
                     std::vector<Patch>& patches) {
  const double cos_tol = std::cos(tolerance), sin_tol = std::sin(tolerance);
  patches.resize(features.moments.size());
  for (std::size_t s = 0; s < patches.size(); ++s) {
    const SegmentMoments& m = features.moments[s];
    Patch& p = patches[s];
    p.centroid = m.mean;
    p.normal = m.normal_sum.squaredNorm() > 0 ? m.normal_sum.normalized() : Eigen::Vector3d::Zero();
    p.radius = 0.5 * std::sqrt(12.0 * std::max(m.scatter.trace() / m.count, 0.0));
    const bool has_normal = m.normal_sum.squaredNorm() > 0;
    p.up = has_normal && p.normal.z() > cos_tol;
    p.down = has_normal && p.normal.z() < -cos_tol;
    p.vertical = has_normal && std::abs(p.normal.z()) < sin_tol;
  }
}

// Close enough to touch: their bounding circles, widened by the gap, meet.
bool touching(const Patch& a, const Patch& b, double gap) {
  return (a.centroid - b.centroid).norm() <= a.radius + b.radius + gap;
}

// A smooth joint: nearly parallel normals with each centroid within `step`
// of the other's plane (not two parallel surfaces at a depth step, a chair
// back before a wall).
bool smooth(const Patch& a, const Patch& b, double cos_smooth, double step) {
  if (a.normal.squaredNorm() == 0 || b.normal.squaredNorm() == 0) return false;
  const Eigen::Vector3d d = a.centroid - b.centroid;
  return a.normal.dot(b.normal) >= cos_smooth && std::abs(a.normal.dot(d)) <= step &&
         std::abs(b.normal.dot(d)) <= step;
}

// LCCP's local convexity: the normals open away from each other along the
// line between the centroids, by more than `margin` (noisy normals of nearly
// flat joints give either sign).
bool convex(const Patch& a, const Patch& b, double margin) {
  if (a.normal.squaredNorm() == 0 || b.normal.squaredNorm() == 0) return false;
  const Eigen::Vector3d d = a.centroid - b.centroid;
  const double length = d.norm();
  return length > 0 && (a.normal - b.normal).dot(d) > margin * length;
}

// The kind of a smooth surface with these pooled moments and height span.
GroupKind surfaceKind(const SegmentMoments& m, double span, const ObjectConfig& config,
                      double tolerance) {
  if (!(m.count > 0) || m.normal_sum.squaredNorm() == 0) return GroupKind::Object;
  const double z = m.normal_sum.normalized().z();
  const double c = m.scatter(0, 0) / m.count, b = m.scatter(0, 1) / m.count,
               d = m.scatter(1, 1) / m.count;
  const double disc = std::sqrt(0.25 * (c - d) * (c - d) + b * b);
  const double major = std::sqrt(12.0 * std::max(0.5 * (c + d) + disc, 0.0));
  const double minor = std::sqrt(12.0 * std::max(0.5 * (c + d) - disc, 0.0));
  if (z > std::cos(tolerance) && m.mean.z() < config.floor_height_m) return GroupKind::Floor;
  if (std::abs(z) < std::sin(tolerance) && major * span >= config.plane_min_area_m2)
    return GroupKind::Wall;
  if (z < -std::cos(tolerance) && major * minor >= config.plane_min_area_m2)
    return GroupKind::Ceiling;
  return GroupKind::Object;
}

// What stands on each object candidate's top (ObjectColumns::Relations): the
// other candidates whose lowest point is near the top's height and whose
// centroid is over its footprint disc. O(G^2) over the groups, a few hundred at most.
void countLoadsOnTops(std::vector<ObjectGroup>& groups) {
  // A thing's lowest point sits on the top, up to the depth noise either way.
  constexpr float kBelowTop = 0.05f, kAboveTop = 0.08f;
  for (ObjectGroup& g : groups) {
    if (g.kind != GroupKind::Object || g.top_area <= 0) continue;
    const Eigen::Vector2f at = g.centroid.head<2>();
    for (const ObjectGroup& h : groups) {
      if (&h == &g || h.kind != GroupKind::Object) continue;
      const bool stands_on_top = h.min_height >= g.top_height - kBelowTop &&
                                 h.min_height <= g.top_height + kAboveTop &&
                                 h.max_height > g.top_height &&
                                 (h.centroid.head<2>() - at).norm() <= 0.5f * g.extent_major;
      if (stands_on_top) ++g.load_on_top;
    }
  }
}

}  // namespace

const ObjectColumnSet& objectColumnSet(ObjectColumns columns) {
  for (const ObjectColumnSet& set : kObjectColumnSets)
    if (set.columns == columns) return set;
  return kObjectColumnSets.front();  // unreachable: every value is in the table
}

std::vector<std::string_view> objectFeatureNames(ObjectColumns columns) {
  std::vector<std::string_view> names;
  for (const int k : objectColumnSet(columns).indices)
    names.push_back(kObjectFeatureNames[static_cast<std::size_t>(k)]);
  return names;
}

const ObjectColumnSet* objectColumnSetWithCount(std::size_t count) {
  for (const ObjectColumnSet& set : kObjectColumnSets)
    if (set.indices.size() == count) return &set;
  return nullptr;
}

ObjectColumns objectColumnsWithCount(std::size_t count) {
  if (const ObjectColumnSet* set = objectColumnSetWithCount(count)) return set->columns;
  throw Error("no object feature column set has " + std::to_string(count) + " columns");
}

void validateObjectConfig(const ObjectConfig& config) {
  auto check = [](float value, double lo, double hi, const char* key) {
    if (!(value >= lo && value <= hi)) {
      throw Error(std::string("features.") + key + " = " + std::to_string(value) + " is outside " +
                  std::to_string(lo) + ".." + std::to_string(hi));
    }
  };
  check(config.concave_tolerance_deg, 0, 90, "objects_concave_tolerance_deg");
  check(config.link_gap_m, 0, 1, "objects_link_gap_m");
  check(config.step_m, 0, 1, "objects_step_m");
  check(config.convex_margin, 0, 2, "objects_convex_margin");
  check(config.floor_height_m, 0, 2, "objects_floor_height_m");
  check(config.plane_min_area_m2, 0, 100, "objects_plane_min_area_m2");
  check(config.orientation_tolerance_deg, 0, 45, "objects_orientation_tolerance_deg");
}

ObjectFeatures computeObjectFeatures(const SegmentFeatures& features,
                                     const Oversegmentation& segmentation,
                                     const RegionFeatures& regions, const ObjectConfig& config) {
  ObjectFeatures out;
  computeObjectFeaturesInto(features, segmentation, regions, config, out);
  return out;
}

namespace {

// Step 1: smooth surfaces, and the large planes among them (or among the coplanar
// regions): floor, walls and ceiling; every other patch an object part.
void surfaceKinds(const SegmentFeatures& features, const Oversegmentation& segmentation,
                  const RegionFeatures& regions, const ObjectConfig& config,
                  const std::vector<Patch>& patches, double tolerance, double cos_smooth,
                  std::vector<int>& parent, std::vector<SegmentMoments>& pooled,
                  std::vector<float>& low, std::vector<float>& high, std::vector<GroupKind>& kind) {
  const std::size_t n = patches.size();
  parent.resize(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [a, b] : segmentation.edges) {
    const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    if (touching(patches[ua], patches[ub], config.link_gap_m) &&
        smooth(patches[ua], patches[ub], cos_smooth, config.step_m))
      unionFindJoin(parent, a, b);
  }
  pooled.assign(n, SegmentMoments{});
  low.assign(n, std::numeric_limits<float>::infinity());
  high.assign(n, -std::numeric_limits<float>::infinity());
  for (std::size_t s = 0; s < n; ++s) {
    const auto root = static_cast<std::size_t>(unionFindRoot(parent, static_cast<int>(s)));
    detail::poolMoments(pooled[root], features.moments[s]);
    low[root] = std::min(low[root], features.features[s][4]);
    high[root] = std::max(high[root], features.features[s][5]);
  }
  kind.resize(n);
  for (std::size_t s = 0; s < n; ++s) {
    const auto root = static_cast<std::size_t>(unionFindRoot(parent, static_cast<int>(s)));
    kind[s] = surfaceKind(pooled[root], high[root] - low[root], config, tolerance);
    if (kind[s] == GroupKind::Object)
      kind[s] = regionKind(regions.values.data() + s * kRegionFeatureDim, config, tolerance);
    if (kind[s] == GroupKind::Object && patches[s].up &&
        patches[s].centroid.z() < config.floor_height_m)
      kind[s] = GroupKind::Floor;
  }
}

// Step 2: groups: the large planes' smooth surfaces and coplanar regions; object
// candidates over convex or smooth joints between touching patches (into `parent`).
void joinGroups(const Oversegmentation& segmentation, const RegionFeatures& regions,
                const ObjectConfig& config, const std::vector<Patch>& patches,
                const std::vector<GroupKind>& kind, double cos_smooth, std::vector<int>& parent,
                std::vector<int>& plane_rep) {
  const std::size_t n = patches.size();
  std::iota(parent.begin(), parent.end(), 0);
  plane_rep.assign(static_cast<std::size_t>(regions.region_count), -1);
  for (std::size_t s = 0; s < n; ++s) {
    if (kind[s] == GroupKind::Object) continue;
    int& rep = plane_rep[static_cast<std::size_t>(regions.segment_region[s])];
    if (rep < 0)
      rep = static_cast<int>(s);
    else if (kind[static_cast<std::size_t>(rep)] == kind[s])
      unionFindJoin(parent, rep, static_cast<int>(s));
  }
  for (const auto& [a, b] : segmentation.edges) {
    const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    if (kind[ua] != kind[ub] || !touching(patches[ua], patches[ub], config.link_gap_m)) continue;
    if (smooth(patches[ua], patches[ub], cos_smooth, config.step_m) ||
        (kind[ua] == GroupKind::Object && convex(patches[ua], patches[ub], config.convex_margin)))
      unionFindJoin(parent, a, b);
  }
}

// Step 3: dense group ids in order of first patch, with their pooled moments, heights,
// centroids and footprints.
void describeGroups(const SegmentFeatures& features, std::vector<int>& parent,
                    const std::vector<GroupKind>& kind, std::vector<int>& root_group,
                    std::vector<SegmentMoments>& pooled, std::vector<FootprintBox>& boxes,
                    ObjectFeatures& out) {
  const std::size_t n = kind.size();
  out.segment_group.assign(n, -1);
  out.groups.clear();
  root_group.assign(n, -1);
  pooled.clear();
  for (std::size_t s = 0; s < n; ++s) {
    const int root = unionFindRoot(parent, static_cast<int>(s));
    if (root_group[static_cast<std::size_t>(root)] < 0) {
      root_group[static_cast<std::size_t>(root)] = static_cast<int>(out.groups.size());
      ObjectGroup group;
      group.kind = kind[s];
      group.min_height = std::numeric_limits<float>::infinity();
      group.max_height = -std::numeric_limits<float>::infinity();
      out.groups.push_back(group);
      pooled.emplace_back();
    }
    const int g = root_group[static_cast<std::size_t>(root)];
    out.segment_group[s] = g;
    ObjectGroup& group = out.groups[static_cast<std::size_t>(g)];
    ++group.segment_count;
    group.min_height = std::min(group.min_height, features.features[s][4]);
    group.max_height = std::max(group.max_height, features.features[s][5]);
    detail::poolMoments(pooled[static_cast<std::size_t>(g)], features.moments[s]);
  }
  boxes.clear();
  for (std::size_t g = 0; g < out.groups.size(); ++g) boxes.emplace_back(majorAxis(pooled[g]));
  for (std::size_t s = 0; s < n; ++s)
    boxes[static_cast<std::size_t>(out.segment_group[s])].add(features.moments[s]);
  for (std::size_t g = 0; g < out.groups.size(); ++g) {
    ObjectGroup& group = out.groups[g];
    group.centroid = pooled[g].mean.cast<float>();
    const auto [major, minor] = boxes[g].extents();
    group.extent_major = static_cast<float>(major);
    group.extent_minor = static_cast<float>(minor);
    group.footprint_area = static_cast<float>(major * minor);
  }
}

// Step 4: the largest up-facing part of each group (its up-facing patches pooled per
// coplanar region): top area and height, and which region it is (top_region).
void largestTops(const SegmentFeatures& features, const RegionFeatures& regions,
                 const std::vector<Patch>& patches, std::vector<int>& tops,
                 std::vector<int>& top_region, ObjectFeatures& out) {
  const std::size_t n = patches.size();
  tops.clear();
  for (std::size_t s = 0; s < n; ++s)
    if (patches[s].up) tops.push_back(static_cast<int>(s));
  const auto by_group_region = [&](int a, int b) {
    const int ga = out.segment_group[static_cast<std::size_t>(a)];
    const int gb = out.segment_group[static_cast<std::size_t>(b)];
    if (ga != gb) return ga < gb;
    const int ra = regions.segment_region[static_cast<std::size_t>(a)];
    const int rb = regions.segment_region[static_cast<std::size_t>(b)];
    return ra != rb ? ra < rb : a < b;
  };
  std::sort(tops.begin(), tops.end(), by_group_region);
  top_region.assign(out.groups.size(), -1);
  for (std::size_t i = 0; i < tops.size();) {
    const auto first = static_cast<std::size_t>(tops[i]);
    const int g = out.segment_group[first];
    const int r = regions.segment_region[first];
    SegmentMoments part;
    const std::size_t begin = i;
    for (; i < tops.size(); ++i) {
      const auto s = static_cast<std::size_t>(tops[i]);
      if (out.segment_group[s] != g || regions.segment_region[s] != r) break;
      detail::poolMoments(part, features.moments[s]);
    }
    FootprintBox box(majorAxis(part));
    for (std::size_t k = begin; k < i; ++k)
      box.add(features.moments[static_cast<std::size_t>(tops[k])]);
    const auto [major, minor] = box.extents();
    ObjectGroup& group = out.groups[static_cast<std::size_t>(g)];
    const auto area = static_cast<float>(major * minor);
    if (top_region[static_cast<std::size_t>(g)] < 0 || area > group.top_area) {
      top_region[static_cast<std::size_t>(g)] = r;
      group.top_area = area;
      group.top_height = static_cast<float>(part.mean.z());
    }
  }
}

// Step 5: what rises above an object's top: the group of a vertical patch touching one
// of its top patches.
void backRises(const Oversegmentation& segmentation, const RegionFeatures& regions,
               const ObjectConfig& config, const std::vector<Patch>& patches,
               const std::vector<int>& top_region, ObjectFeatures& out) {
  const auto rise = [&](std::size_t top, std::size_t side) {
    const int g = out.segment_group[top];
    ObjectGroup& group = out.groups[static_cast<std::size_t>(g)];
    if (group.kind != GroupKind::Object || !patches[top].up || !patches[side].vertical) return;
    if (regions.segment_region[top] != top_region[static_cast<std::size_t>(g)]) return;
    const ObjectGroup& other = out.groups[static_cast<std::size_t>(out.segment_group[side])];
    if (other.kind != GroupKind::Object) return;
    if (!touching(patches[top], patches[side], config.link_gap_m)) return;
    group.back_rise = std::max(group.back_rise, other.max_height - group.top_height);
  };
  for (const auto& [a, b] : segmentation.edges) {
    rise(static_cast<std::size_t>(a), static_cast<std::size_t>(b));
    rise(static_cast<std::size_t>(b), static_cast<std::size_t>(a));
  }
}

// Step 6: the nearest wall: each wall group is a segment on the ground, along its
// major extent, across its mean normal.
void wallDistances(const std::vector<SegmentMoments>& pooled, ObjectFeatures& out) {
  for (std::size_t w = 0; w < out.groups.size(); ++w) {
    if (out.groups[w].kind != GroupKind::Wall) continue;
    const Eigen::Vector2d normal = pooled[w].normal_sum.head<2>();
    if (normal.squaredNorm() == 0) continue;
    const Eigen::Vector2d along = Eigen::Vector2d(-normal.y(), normal.x()).normalized();
    const Eigen::Vector2d centre = pooled[w].mean.head<2>();
    const double half = 0.5 * out.groups[w].extent_major;
    for (ObjectGroup& group : out.groups) {
      const Eigen::Vector2d d = group.centroid.head<2>().cast<double>() - centre;
      const double t = std::clamp(along.dot(d), -half, half);
      const double distance = (d - t * along).norm();
      group.wall_distance = std::min(group.wall_distance, static_cast<float>(distance));
    }
  }
}

// Step 7: each patch's row: its group's columns of config.columns.
void writeRows(const std::vector<Patch>& patches, ObjectColumns column_set, ObjectFeatures& out) {
  const std::size_t n = patches.size();
  const std::span<const int> columns = objectColumnSet(column_set).indices;
  const std::size_t dim = columns.size();
  out.values.resize(n * dim);
  for (std::size_t s = 0; s < n; ++s) {
    const ObjectGroup& g = out.groups[static_cast<std::size_t>(out.segment_group[s])];
    const float span = g.max_height - g.min_height;
    const float relative = std::clamp(
        (static_cast<float>(patches[s].centroid.z()) - g.min_height) / std::max(span, 0.01f), 0.0f,
        1.0f);
    std::array<float, kObjectFeatureCount> row;
    row[0] = span;
    row[1] = g.min_height;
    row[2] = g.footprint_area;
    row[3] = g.extent_major;
    row[4] = g.extent_minor;
    row[5] = g.top_height;
    row[6] = g.top_area;
    row[7] = g.back_rise;
    row[8] = g.wall_distance;
    row[9] = static_cast<float>(static_cast<int>(g.kind));
    row[10] = relative;
    row[11] = static_cast<float>(g.load_on_top);
    float* out_row = out.values.data() + s * dim;
    for (std::size_t k = 0; k < dim; ++k) out_row[k] = row[static_cast<std::size_t>(columns[k])];
  }
}

}  // namespace

void computeObjectFeaturesInto(const SegmentFeatures& features,
                               const Oversegmentation& segmentation, const RegionFeatures& regions,
                               const ObjectConfig& config, ObjectFeatures& out) {
  validateObjectConfig(config);
  checkInputs(features, segmentation, regions);
  const double tolerance = config.orientation_tolerance_deg * M_PI / 180.0;
  const double cos_smooth = std::cos(config.concave_tolerance_deg * M_PI / 180.0);

  thread_local std::vector<Patch> patches_tls;
  thread_local std::vector<GroupKind> kind_tls;
  thread_local std::vector<int> parent_tls, root_group_tls, plane_rep_tls, tops_tls, top_region_tls;
  thread_local std::vector<SegmentMoments> pooled_tls;
  thread_local std::vector<FootprintBox> boxes_tls;
  thread_local std::vector<float> low_tls, high_tls;
  detail::Borrowed patches_buffer(patches_tls);
  detail::Borrowed kind_buffer(kind_tls);
  detail::Borrowed parent_buffer(parent_tls), root_group_buffer(root_group_tls);
  detail::Borrowed plane_rep_buffer(plane_rep_tls), tops_buffer(tops_tls);
  detail::Borrowed top_region_buffer(top_region_tls);
  detail::Borrowed pooled_buffer(pooled_tls);
  detail::Borrowed boxes_buffer(boxes_tls);
  detail::Borrowed low_buffer(low_tls), high_buffer(high_tls);
  std::vector<Patch>& patches = *patches_buffer;
  describePatches(features, tolerance, patches);

  surfaceKinds(features, segmentation, regions, config, patches, tolerance, cos_smooth,
               *parent_buffer, *pooled_buffer, *low_buffer, *high_buffer, *kind_buffer);
  joinGroups(segmentation, regions, config, patches, *kind_buffer, cos_smooth, *parent_buffer,
             *plane_rep_buffer);
  describeGroups(features, *parent_buffer, *kind_buffer, *root_group_buffer, *pooled_buffer,
                 *boxes_buffer, out);
  largestTops(features, regions, patches, *tops_buffer, *top_region_buffer, out);
  backRises(segmentation, regions, config, patches, *top_region_buffer, out);
  wallDistances(*pooled_buffer, out);
  if (config.columns == ObjectColumns::Relations) countLoadsOnTops(out.groups);
  writeRows(patches, config.columns, out);
}

void objectCandidatesInto(const ObjectFeatures& objects, std::vector<int>& out) {
  out.resize(objects.segment_group.size());
  for (std::size_t s = 0; s < out.size(); ++s) {
    const int g = objects.segment_group[s];
    const bool candidate = g >= 0 && static_cast<std::size_t>(g) < objects.groups.size() &&
                           objects.groups[static_cast<std::size_t>(g)].kind == GroupKind::Object;
    out[s] = candidate ? g : -1;
  }
}

}  // namespace findmug
