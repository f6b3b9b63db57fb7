// findmug/features/object_features.hpp — 3-D object candidates and the features of a patch's object.
//
// A patch says little about whether it is part of a chair, a table or a
// cabinet; the thing it belongs to says more: how tall it is, how large its
// top is, whether a back rises behind its seat. Patches are grouped into
// object candidates in the ground frame, from the segments' moments (no pass
// over the pixels):
//  1. Smooth surfaces: patches joined over the adjacency graph where they
//     touch (centroid distance at most the sum of their radii, half the
//     diagonal of the rectangle with a patch's variances, plus `link_gap_m`)
//     and the joint is smooth: unit normals within `concave_tolerance_deg` of
//     each other and each centroid within `step_m` of the other's plane (not
//     two parallel surfaces at a depth step, a chair back before a wall).
//  2. Large planes are kept out of objects: a smooth surface (or a coplanar
//     region of region_features.hpp, formed with the features.region_*
//     thresholds) that faces up below `floor_height_m` is floor, one that is
//     vertical with major extent x height span at least `plane_min_area_m2`
//     is wall, one that faces down with a footprint that large is ceiling;
//     an up-facing patch below `floor_height_m` is floor too. Each such
//     surface or region is one group of its own kind.
//  3. Object candidates: the other patches joined where they touch and the
//     joint is smooth or convex (local convexity, as in LCCP segmentation):
//     with centroids c and normals n (facing the camera, so outwards on what
//     it sees), (n_a - n_b) . (c_a - c_b) > `convex_margin` |c_a - c_b| (a
//     margin, because the noisy normals of nearly flat joints give either
//     sign). Concave joints split: a box on a table, a drawer unit beside a
//     desk. The connected components are the object candidates.
// Per group, from the pooled moments of its patches:
//   object_height_span       highest minus lowest point (m)
//   object_min_height        lowest point (m): standing on the floor or not
//   object_footprint_area    major x minor side of its footprint box on the
//   object_extent_major      ground (m², m, m): along the principal axes of
//   object_extent_minor      its points' 2-D scatter, around every patch taken
//                            as a uniform rectangle of its variances (so a
//                            table's legs do not widen its top)
//   object_top_height        height (m) and footprint area (m²) of its largest
//   object_top_area          horizontal up-facing part (patches of one coplanar
//                            region); 0 and 0 without one
//   object_back_rise         how far a vertical part rises above that top (m):
//                            the highest point of any group joined to the top
//                            by an edge from a top patch to a vertical patch
//                            (a chair back, a bed head, also a box on a table);
//                            0 when nothing rises (> 0: "vertical above
//                            horizontal")
//   object_wall_distance     horizontal distance from its centroid to the
//                            nearest wall segment (m); kNoWallDistance without
//                            a wall
//   object_kind              0 object, 1 floor, 2 wall, 3 ceiling
//   patch_height_in_object   the patch's centroid height above the group's
//                            lowest point over its height span (0..1): a seat
//                            sits in the middle of a chair, a table top at the top
// and, from the candidates around it (features.objects_columns = relations):
//   object_load_on_top       how many other candidates stand on its top (lowest
//                            point within -0.05..+0.08 m of the top's height,
//                            centroid within half its major extent of its
//                            centroid); 0 without a top: a table holds things,
//                            a chair seat rarely does
// Cost: two union-finds over the edges and a few passes over the patches.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "findmug/features/features.hpp"
#include "findmug/features/region_features.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"

namespace findmug {

// Which of the object features a patch's row gets (features.objects_columns).
enum class ObjectColumns {
  All,      // all kObjectFeatureDim
  Context,  // the three that say where the patch sits in its object and the room:
            // object_back_rise, object_wall_distance, patch_height_in_object
  Relations,  // those three and what stands on its object: object_load_on_top
};

struct ObjectConfig {
  bool enabled = false;                     // features.objects
  ObjectColumns columns = ObjectColumns::All;  // features.objects_columns
  float concave_tolerance_deg = 15.0f;      // features.objects_concave_tolerance_deg
  float link_gap_m = 0.05f;                 // features.objects_link_gap_m
  float step_m = 0.1f;                      // features.objects_step_m
  float convex_margin = 0.3f;               // features.objects_convex_margin
  float floor_height_m = 0.15f;             // features.objects_floor_height_m
  float plane_min_area_m2 = 1.0f;           // features.objects_plane_min_area_m2
  float orientation_tolerance_deg = 25.0f;  // features.objects_orientation_tolerance_deg
};

// Every object feature; ObjectColumns::All is the first kObjectFeatureDim of them
// (the set models with "all" were trained on), the relational one follows.
inline constexpr int kObjectFeatureDim = 11;
inline constexpr int kObjectFeatureCount = 12;
inline constexpr std::array<std::string_view, kObjectFeatureCount> kObjectFeatureNames = {
    "object_height_span",     "object_min_height",      "object_footprint_area",
    "object_extent_major",    "object_extent_minor",    "object_top_height",
    "object_top_area",        "object_back_rise",       "object_wall_distance",
    "object_kind",            "patch_height_in_object", "object_load_on_top"};

// The columns of each ObjectColumns set, as indices into kObjectFeatureNames.
inline constexpr std::array<int, kObjectFeatureDim> kObjectAllColumns = {0, 1, 2, 3, 4, 5,
                                                                        6, 7, 8, 9, 10};
inline constexpr std::array<int, 3> kObjectContextColumns = {7, 8, 10};
inline constexpr std::array<int, 4> kObjectRelationsColumns = {7, 8, 10, 11};

// The column sets: the setting's word (features.objects_columns) and the columns, in row order.
struct ObjectColumnSet {
  ObjectColumns columns;
  std::string_view name;
  std::span<const int> indices;
};
inline constexpr std::array<ObjectColumnSet, 3> kObjectColumnSets = {{
    {ObjectColumns::All, "all", kObjectAllColumns},
    {ObjectColumns::Context, "context", kObjectContextColumns},
    {ObjectColumns::Relations, "relations", kObjectRelationsColumns},
}};

// The set `columns` names (never fails: every enum value has one).
const ObjectColumnSet& objectColumnSet(ObjectColumns columns);
// The names of the columns `columns` selects, in row order.
std::vector<std::string_view> objectFeatureNames(ObjectColumns columns);
// The column set with `count` columns per patch, or nullptr when none has.
const ObjectColumnSet* objectColumnSetWithCount(std::size_t count);
// The same, throwing findmug::Error when none has.
ObjectColumns objectColumnsWithCount(std::size_t count);

// object_wall_distance when the frame has no wall (m).
inline constexpr float kNoWallDistance = 10.0f;

enum class GroupKind { Object = 0, Floor = 1, Wall = 2, Ceiling = 3 };

struct ObjectGroup {
  GroupKind kind = GroupKind::Object;
  int segment_count = 0;
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  // ground frame (m)
  float min_height = 0, max_height = 0;                // m
  float footprint_area = 0, extent_major = 0, extent_minor = 0;
  float top_height = 0, top_area = 0;  // largest horizontal up-facing part; 0, 0 without one
  float back_rise = 0;                 // m; > 0 when a vertical part rises above the top
  float wall_distance = kNoWallDistance;
  int load_on_top = 0;                 // candidates standing on its top (Relations only)
};

struct ObjectFeatures {
  std::vector<int> segment_group;  // segment -> index into groups
  std::vector<ObjectGroup> groups;  // object candidates and the large planes (kind)
  // Row-major, objectFeatureNames(config.columns).size() per segment.
  std::vector<float> values;
};

// Per segment of `objects`, the index of its group when that group is an
// object candidate, -1 when it is a floor, wall or ceiling plane
// (SegmentFeatures::object_group), into `out`.
void objectCandidatesInto(const ObjectFeatures& objects, std::vector<int>& out);

// Throws findmug::Error naming the setting when a value is out of range.
void validateObjectConfig(const ObjectConfig& config);

// `features` are the segments' base features with their moments
// (computeFeatures of `segmentation`); `regions` the smooth coplanar regions of
// the same segmentation (computeRegionFeatures, any features.regions setting
// but the same segments). Throws findmug::Error when the counts disagree, an
// edge names a segment outside them, or a segment's moments are empty or not
// finite. No segments give empty output.
ObjectFeatures computeObjectFeatures(const SegmentFeatures& features,
                                     const Oversegmentation& segmentation,
                                     const RegionFeatures& regions, const ObjectConfig& config);
// The same into `out`, reusing the memory it holds.
void computeObjectFeaturesInto(const SegmentFeatures& features,
                               const Oversegmentation& segmentation,
                               const RegionFeatures& regions, const ObjectConfig& config,
                               ObjectFeatures& out);

}  // namespace findmug
