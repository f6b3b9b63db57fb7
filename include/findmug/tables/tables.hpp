// findmug/tables/tables.hpp — table clusters and search positions (object search).
//
// Everything here is in the ground-aligned frame of ground.hpp (z up, floor
// at z = 0, x forward from below the camera): the robot base frame when the
// camera mount is known.
//
// Steps of findTables / detectTables, per labelled frame:
//   1. table points: label Table, finite coordinates, height within
//      [min_table_height_m, max_table_height_m];
//   2. Euclidean clustering with `cluster_tolerance_m` (exact: two points are
//      in one cluster iff a chain of points links them with gaps no larger
//      than the tolerance), clusters outside [min, max]_cluster_points dropped;
//   3. per cluster: top height (densest height band), the top's points, PCA of
//      the top projected on the floor (on a 2 cm occupancy grid, so that the
//      denser near part of a table does not pull the axes), oriented box
//      (edges robust to depth noise: a high quantile of per-strip extremes),
//      convex hull of the top's points;
//   4. search positions (Wolf et al. 2014): on the second principal axis, on
//      both sides, `safety_distance_m` from the table edge, facing the table;
//      long tables get more positions along their long sides so that the top
//      is within `arm_reach_m` of one of them (see computeSearchPositions);
//   3b. the table-top test (a bed or sofa is not a table): a cluster whose
//      top is at least `soft_top_min_area_m2` and whose top's near-horizontal
//      normals (within `horizontal_tilt_deg` of vertical) are mostly not
//      within `flat_tilt_deg` (share below `min_flat_share`) is a soft,
//      undulating surface, not a hard flat top: dropped with a reason, and
//      its pixels listed in TableDetection::soft_top_pixels for
//      relabelSoftTops;
//   5. reachability of each position from the same labelled cloud: an
//      obstacle (non-floor points between `obstacle_min_height_m` and
//      `robot_height_m`) within `robot_radius_m`, or too little observed floor
//      under the robot's footprint, makes it unreachable with a reason. Such
//      positions are kept and flagged, never silently dropped.
// Point stride: with tables.point_stride s > 1, steps 2 and 3 run on the
// table points at every s-th pixel of every s-th row (a quarter of them for
// s = 2: the stage's cost is mostly per point, and a table top 1-4 m away
// has points every 2-8 mm, far below the 5 cm tolerance). Every other table
// point then joins the cluster of the first sampled corner of its s x s cell
// (top left, top right, bottom left, bottom right) within
// cluster_tolerance_m; those with none are left out and counted in the
// diagnostics. Pixels, point counts, confidence and the horizontal share
// stay those of the full-resolution cluster; only the geometry of step 3
// (top height, axes, edges, hull, top area) is computed from the samples,
// which holds it to within about a sample spacing in the middle of a top;
// but at a far, sparse edge the robust edges (table_geometry.cpp) move
// inwards, and the top area shrinks by the cells that only unsampled points
// reach. Two parts of a table joined only through unsampled points split (a
// bridge one pixel wide at s = 2).
// Anything skipped (no ground-aligned cloud, non-finite points, degenerate or
// out-of-size clusters) is reported in TableDetection::diagnostics for the
// caller to log; the core library itself does not log.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/labels/label_image.hpp"

namespace findmug {

struct SearchPosition {
  Eigen::Vector2f xy = Eigen::Vector2f::Zero();  // on the floor, metres
  float yaw = 0.0f;                              // rad, facing the table
  bool reachable = true;
  std::string reason;  // why unreachable ("obstacle within robot radius", "no observed floor")
  // Which long side of the table (+1: along +minor_axis, -1: along -minor_axis)
  // and the offset along major_axis from the box centre, metres.
  int side = 1;
  float along_m = 0.0f;
};

struct TableCluster {
  int id = 0;  // findTables: 0..n-1 by decreasing point count; TableMap: the stable id
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  // mean of the top's points
  float top_height = 0.0f;
  // First principal axis (unit, floor plane) and the second one (major
  // turned +90°); half-lengths of the top along them.
  Eigen::Vector2f major_axis = Eigen::Vector2f::UnitX();
  Eigen::Vector2f minor_axis = Eigen::Vector2f::UnitY();
  Eigen::Vector2f extents = Eigen::Vector2f::Zero();
  // Centre of the oriented box (major/minor axes, extents) on the floor. It
  // differs from the centroid's x,y when the points are unevenly spread.
  Eigen::Vector2f center = Eigen::Vector2f::Zero();
  std::vector<Eigen::Vector2f> hull;  // convex hull of the top, CCW
  // The visible top's size: floor area of the cells (tables.cluster_tolerance_m
  // on a side) that hold top points; a vertical panel's top band is a thin line.
  float top_area_m2 = 0.0f;
  // Share of the cluster's points whose normal is within
  // tables.horizontal_tilt_deg of vertical (NaN when detectTables had no
  // normals): table tops are horizontal, chair backs and cabinet fronts not.
  float horizontal_share = std::numeric_limits<float>::quiet_NaN();
  // The table-top test's measure (step 3b): of the top's points (within
  // tables.top_band_m of top_height) whose normal is within
  // tables.horizontal_tilt_deg of vertical, the share within
  // tables.flat_tilt_deg. A hard top's near-horizontal normals are all
  // nearly vertical; a blanket's spread. Measured on the horizontal part
  // only, so that chair backs or a cabinet front in the cluster do not
  // count. NaN where it is not measured: without normals, for a top smaller
  // than tables.soft_top_min_area_m2, or with no horizontal top point.
  float flat_share = std::numeric_limits<float>::quiet_NaN();
  int point_count = 0;
  // Image pixels (y * width + x) of all the cluster's points, ascending: its
  // image mask, for matching against ground truth (table_metrics.hpp).
  std::vector<int> pixels;
  float mean_confidence = 0.0f;
  std::vector<SearchPosition> search_positions;
};

struct TableConfig {
  float cluster_tolerance_m = 0.05f;
  // Point counts are of the full-resolution cluster (every table pixel).
  int min_cluster_points = 500;
  int max_cluster_points = 1000000;  // above a VGA frame: a close table may fill the view
  // Pixel stride of the points that steps 2 and 3 work on (see "Point
  // stride" above). 1 = every table point (the exact definition of step 2).
  // 2 takes about 40 % off the stage on table-rich views but costs table
  // instances on NYU (perf-log §9j): a knob for a tight CPU budget.
  int point_stride = 1;
  float safety_distance_m = 0.5f;    // d: from the table edge to the search position
  float arm_reach_m = 0.8f;
  float robot_radius_m = 0.3f;
  float min_table_height_m = 0.3f;
  float max_table_height_m = 1.3f;
  // Points within this height of the top height form the top (hull, axes, extents).
  float top_band_m = 0.05f;
  // Clusters whose top is narrower than this along the second axis (a line
  // of points, a single point) are degenerate and dropped with a reason.
  float min_table_width_m = 0.1f;
  // Obstacle test: non-floor points with height in [obstacle_min_height_m,
  // robot_height_m] within robot_radius_m of a position; at least
  // obstacle_min_points of them (a few stray points are sensor noise).
  float obstacle_min_height_m = 0.05f;
  float robot_height_m = 1.4f;
  int obstacle_min_points = 5;
  // Floor test: floor-labelled points within floor_tolerance_m of z = 0 mark
  // floor_cell_m cells as observed; a position needs at least
  // min_floor_observed_fraction of the cells under its footprint observed.
  float floor_tolerance_m = 0.1f;
  float floor_cell_m = 0.1f;
  float min_floor_observed_fraction = 0.5f;
  // Region vote before clustering (table_regions.hpp; needs a model with
  // region features): each horizontal region at table height gets one label.
  // Off: on the 31 NYU frames it changed no match (perf-log §1f).
  bool region_vote = false;
  // Bias of the label decision towards tables (weightTableProbability in
  // table_regions.hpp): p(table) times this before the MRF. 1 = none; 1.5
  // measured best on the 31 NYU frames (perf-log §1f).
  float table_weight = 1.5f;
  float region_max_tilt_deg = 15.0f;  // region normal within this of vertical
  float region_min_area_m2 = 0.04f;   // smaller regions keep their patches' labels
  // Detection filters (after the geometry): a table needs a visible top of at
  // least min_top_area_m2 (TableCluster::top_area_m2; a vertical panel or a
  // chair back has almost none) and a mean label confidence of at least
  // min_confidence. Dropped clusters are reported in the diagnostics.
  float min_top_area_m2 = 0.15f;
  float min_confidence = 0.0f;
  // With normals: at least min_horizontal_share of a table's points must
  // have a normal within horizontal_tilt_deg of vertical.
  float min_horizontal_share = 0.2f;
  float horizontal_tilt_deg = 20.0f;
  // The table-top test (step 3b; needs normals): a top of at least
  // soft_top_min_area_m2 (bed- or sofa-sized as far as a view shows it)
  // whose flat_share (TableCluster) is below min_flat_share is not a table.
  // On NYU's labelled frames with the shipped model (BENCHMARKS.md §1, "What
  // becomes table"), the bed tops labelled table have flat shares of
  // 0.16-0.45; the table, desk and counter tops of that size 0.67-0.95, and
  // the largest mostly false cluster that still covers a true table 0.50.
  // flat_tilt_deg must not be above horizontal_tilt_deg. min_flat_share 0
  // turns the test off.
  float soft_top_min_area_m2 = 0.5f;
  float flat_tilt_deg = 10.0f;
  float min_flat_share = 0.47f;
  // Whether the Segmenter labels the pixels of a cluster that fails the
  // table-top test Unknown (relabelSoftTops): NYU's bed and sofa are Unknown.
  bool relabel_soft_tops = true;
};

// Why something produced no table or was flagged, for the caller to log.
struct TableDetection {
  std::vector<TableCluster> tables;
  std::vector<std::string> diagnostics;  // one human-readable line per reason
  int table_points = 0;                  // table-labelled points at table height (all pixels)
  int nonfinite_points = 0;              // table-labelled points with a NaN/inf coordinate
  int implausible_points = 0;            // table-labelled points outside the height range or
                                         // absurdly far (> 100 m) from the robot
  int clusters_rejected = 0;             // clusters dropped (size, degenerate)
  // With tables.point_stride > 1: table points with no sampled point within
  // cluster_tolerance_m among their cell's corners, left out of every cluster.
  int unsampled_points = 0;
  // Clusters that failed the table-top test (step 3b) and their pixels,
  // ascending within each cluster (also counted in clusters_rejected).
  int soft_tops = 0;
  std::vector<int> soft_top_pixels;
};

// Labels Unknown the table-labelled pixels of the clusters that failed the
// table-top test (detection.soft_top_pixels): a bed or sofa is neither a
// table nor a search location. Returns how many pixels changed; throws
// findmug::Error for a pixel outside `labels` (the image is then unchanged).
int relabelSoftTops(const TableDetection& detection, LabelImage& labels);

// Throws findmug::Error naming the setting (`tables.KEY = value: rule`) when
// a setting is out of range or inconsistent with another. detectTables calls
// it; a daemon can call it once at start-up to fail early.
void validateTableConfig(const TableConfig& config);

// Throws findmug::Error when `labels` and `cloud_ground` disagree in size or
// a setting is out of range (message names the setting). An empty cloud
// means "no ground plane for this frame": no tables, with that reason.
//
// `normals_ground` (optional, the cloud's normals in the ground frame) gives
// each table its horizontal_share; without it the share stays NaN and
// tables.min_horizontal_share is not applied.
TableDetection detectTables(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                            const TableConfig& config,
                            const NormalImage* normals_ground = nullptr);
// The same into `out`, whose tables (from an earlier frame) lend their
// buffers (pixel lists, hulls) to this frame's: a stream of frames then
// allocates almost nothing here once warm. Every field of `out` is replaced.
void detectTablesInto(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                      const TableConfig& config, const NormalImage* normals_ground,
                      TableDetection& out);

// detectTables(...).tables, for callers that do not log the reasons.
std::vector<TableCluster> findTables(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                                     const TableConfig& config);

// The search positions of a table from its box alone (centre, axes,
// extents), all marked reachable: on both sides along the second axis, at
// `safety_distance_m` from the edge, facing the table. Along each long side
// there are n = max(1, ceil(extent_major / h)) positions spread evenly, with
// h the half-length of edge a position covers: h = sqrt(r^2 - (d + w)^2)
// when the arm reaches the midline of the top (r = arm_reach_m, d =
// safety_distance_m, w = half-width), else sqrt(r^2 - d^2) (the edge strip
// is covered). n = 1 is the paper's single position per side. When r <= d no
// extra positions are added. Order: side +1 then -1, each by `along_m`.
std::vector<SearchPosition> computeSearchPositions(const TableCluster& table,
                                                   const TableConfig& config);

// Exact Euclidean clustering: cluster index (0..k-1, in order of first
// appearance) of each point, where two points share a cluster iff a chain of
// points links them with steps of at most `tolerance`. Same partition as PCL's
// EuclideanClusterExtraction before its size filter, in O(n) on a hashed voxel
// grid. Points must be finite and within 100 m of the origin, the tolerance
// at least 1 mm (else Error).
std::vector<int> euclideanClusterLabels(const std::vector<Eigen::Vector3f>& points,
                                        float tolerance);

// Convex hull of 2-D points, counter-clockwise, without collinear points.
std::vector<Eigen::Vector2f> convexHull2d(std::vector<Eigen::Vector2f> points);

}  // namespace findmug
