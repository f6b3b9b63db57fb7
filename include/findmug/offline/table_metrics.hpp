// findmug/offline/table_metrics.hpp — table detection measured as objects, the way a
// navigation client consumes it (tables and search positions, not pixels).
//
// Ground truth: the table instances of a frame are the clusters that
// detectTables finds on the GROUND-TRUTH label image (3-D connected
// components of table-labelled points at table height, linked within
// tables.cluster_tolerance_m), keeping those of at least
// `min_instance_points` points. findmug-eval clusters them with the built-in
// `TableConfig{}` (the shipped values), whatever tables.* it evaluates, so
// that changing a table setting changes what is found, not what is there.
// Their geometry (top height, centroid, principal axis) is computed exactly
// as for detected tables, so that a perfect labelling has zero error.
//
// Matching: a detected table (a TableCluster from the Segmenter, its image
// mask = TableCluster::pixels) matches a ground-truth instance when their
// masks overlap with IoU >= `min_iou`; one-to-one, greedily by decreasing
// IoU. Precision = matched / detected, recall = matched / ground truth,
// summed over frames. For matched pairs: |top height difference|,
// horizontal distance of the centroids, and the angle between the principal
// axes modulo 180 degrees (0..90).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/settings/offline_settings.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {


// Throws findmug::Error naming `table_metrics.KEY` when a setting is out of range.
void validateTableMetricsConfig(const TableMetricsConfig& config);

// The ground-truth table instances of a frame (see above): detectTables on
// `gt_labels` with `tables` settings, min_cluster_points raised to
// `min_instance_points`. `cloud_ground` empty (no ground frame): none.
std::vector<TableCluster> groundTruthTables(const OrganizedCloud& cloud_ground,
                                            const std::vector<std::uint8_t>& gt_labels,
                                            const TableConfig& tables,
                                            const TableMetricsConfig& config);

// How many values two sorted pixel lists share (masks as TableCluster::pixels).
std::size_t sortedIntersectionSize(const std::vector<int>& a, const std::vector<int>& b);

// IoU of two image masks given as sorted pixel indices (0 when both empty).
double maskIoU(const std::vector<int>& a, const std::vector<int>& b);

struct TableMatch {
  int truth = -1;     // index into the ground-truth tables
  int detected = -1;  // index into the detected tables
  double iou = 0.0;
  float height_error_m = 0.0f;    // |top height difference|
  float centroid_error_m = 0.0f;  // horizontal distance of the centroids
  float axis_error_deg = 0.0f;    // principal axes, modulo 180 degrees: 0..90
};

// One-to-one greedy matching by decreasing IoU, pairs with IoU >= min_iou.
std::vector<TableMatch> matchTables(const std::vector<TableCluster>& truth,
                                    const std::vector<TableCluster>& detected, float min_iou);

// Sums over frames.
class TableMetrics {
 public:
  void add(int truth_tables, int detected_tables, const std::vector<TableMatch>& matches);
  int truth() const { return truth_; }
  int detected() const { return detected_; }
  int matched() const { return static_cast<int>(height_errors_.size()); }
  double precision() const;  // NaN without detections
  double recall() const;     // NaN without ground-truth tables
  // Medians over matched pairs (NaN without matches).
  double medianHeightError() const;
  double medianCentroidError() const;
  double medianAxisErrorDeg() const;
  const std::vector<float>& heightErrors() const { return height_errors_; }
  const std::vector<float>& centroidErrors() const { return centroid_errors_; }
  const std::vector<float>& axisErrorsDeg() const { return axis_errors_; }

 private:
  int truth_ = 0, detected_ = 0;
  std::vector<float> height_errors_, centroid_errors_, axis_errors_;
};

// ---------------------------------------------------------------------------
// Tables a robot can search: the true instances whose visible top
// (TableCluster::top_area_m2 of the ground-truth points, in the ground frame)
// is at least `searchable_min_top_area_m2`. A detection matches a true table
// (any instance, searchable or not) by top overlap: the area common to the two
// tops' convex hulls on the floor, over the smaller hull's area, at least
// `searchable_min_overlap`, with top heights within
// `searchable_max_height_error_m`; one-to-one, greedily by decreasing
// overlap. Recall = searchable tables matched / searchable tables. Precision
// = detections matching a searchable table / detections, leaving out those
// that match a true table too small to be searchable (neither right nor
// wrong). A detection matching no true table is a false table.

// Area common to two convex polygons (CCW or CW), by clipping one with the other.
double convexOverlapArea(const std::vector<Eigen::Vector2f>& a,
                         const std::vector<Eigen::Vector2f>& b);
// Common area over the smaller top's hull area (polygonArea of table_map.hpp) (0 when either is degenerate).
double topOverlap(const TableCluster& a, const TableCluster& b);

// One frame's searchable-table figures (see above).
struct SearchableFrame {
  int searchable = 0;          // true tables with a large enough top
  int searchable_matched = 0;  // of them, matched by a detection
  int detected = 0;            // all detections
  int detected_small = 0;      // detections matching a true table that is not searchable
  int false_tables = 0;        // detections matching no true table
};
SearchableFrame measureSearchableTables(const std::vector<TableCluster>& truth,
                                        const std::vector<TableCluster>& detected,
                                        const TableMetricsConfig& config);

// Sums over frames.
class SearchableMetrics {
 public:
  void add(const SearchableFrame& frame);
  int frames() const { return frames_; }
  int searchable() const { return searchable_; }
  int matched() const { return matched_; }
  int detected() const { return detected_; }
  int detectedSmall() const { return detected_small_; }
  int falseTables() const { return false_tables_; }
  int framesWithFalseTable() const { return frames_with_false_; }
  double precision() const;             // NaN when no detection counts
  double recall() const;                // NaN without searchable tables
  double falseTableFrameShare() const;  // NaN without frames

 private:
  int frames_ = 0, searchable_ = 0, matched_ = 0, detected_ = 0, detected_small_ = 0,
      false_tables_ = 0, frames_with_false_ = 0;
};

// ---------------------------------------------------------------------------
// Precision/recall over a detection score threshold.

// One detection with its score (TableCluster::mean_confidence in
// findmug-eval) and whether it matched a true instance.
struct ScoredDetection {
  float score = 0.0f;
  bool matched = false;
};

// The figures if only detections with score >= threshold were kept.
// Matches do not change with the threshold: detections are disjoint, so
// (but for exact ties of IoU 0.5) each matches the same instance, or none,
// whichever others are kept.
struct PrecisionRecallPoint {
  float threshold = 0.0f;
  int detected = 0, matched = 0;
  double precision = 0.0;  // NaN when nothing is kept
  double recall = 0.0;     // NaN without true instances
};

// One point per distinct score, by decreasing threshold (so increasing
// recall); `truth` = the number of true instances. Throws findmug::Error for
// a non-finite score or a negative `truth`.
std::vector<PrecisionRecallPoint> precisionRecallCurve(std::vector<ScoredDetection> detections,
                                                       int truth);

// The point of highest recall whose precision is at least `min_precision`
// (ties: the higher precision, then the higher threshold); nullptr when no
// point reaches it.
const PrecisionRecallPoint* operatingPoint(const std::vector<PrecisionRecallPoint>& curve,
                                           double min_precision);

// ---------------------------------------------------------------------------
// Search positions against exactly known tables (synthetic scenes).

// The search positions of a table whose top is known exactly: a box with
// centre, yaw (of its long side, `size` = length, width) in the ground frame,
// through computeSearchPositions, as for a detected table.
std::vector<SearchPosition> searchPositionsOfBox(const Eigen::Vector2f& center, float yaw,
                                                 const Eigen::Vector2f& size, float height,
                                                 const TableConfig& config);

struct PositionError {
  int nearest = -1;            // index into the true positions, -1 when there are none
  float distance_m = 0.0f;     // to the nearest true position, on the floor
  float yaw_error_deg = 0.0f;  // |yaw difference| to it, wrapped to 0..180
};

// For each predicted position, the nearest true position (by floor distance).
std::vector<PositionError> nearestPositionErrors(const std::vector<SearchPosition>& predicted,
                                                 const std::vector<SearchPosition>& truth);

// Sums over frames: predicted positions, their errors, and how many of them
// are reachable in the true scene (e.g. synth::robotFits), of all and of
// those the Segmenter flagged reachable (SearchPosition::reachable).
class SearchPositionMetrics {
 public:
  // One entry per predicted position in each vector; throws findmug::Error
  // when the sizes differ.
  void add(const std::vector<PositionError>& errors, const std::vector<bool>& flagged_reachable,
           const std::vector<bool>& reachable_in_truth);
  int predicted() const { return predicted_; }
  int reachableInTruth() const { return reachable_; }
  int flaggedReachable() const { return flagged_; }
  int flaggedReachableInTruth() const { return flagged_truly_; }
  double reachableShare() const;         // of all predictions; NaN without any
  double flaggedReachableShare() const;  // of those flagged reachable; NaN without any
  double medianPositionError() const;    // NaN without predictions that have a true one
  double medianYawErrorDeg() const;

 private:
  int predicted_ = 0, reachable_ = 0, flagged_ = 0, flagged_truly_ = 0;
  std::vector<float> distances_, yaw_errors_;
};

}  // namespace findmug
