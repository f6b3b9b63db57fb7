// tables_internal.hpp — internal to findmug_core (not installed): what the
// table files share. tables.cpp (detectTables) calls the clustering of
// table_clustering.cpp, the per-cluster geometry of table_geometry.cpp and
// the reachability grid of table_reachability.cpp; the limits and helpers
// below are common to them.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "common/floor_to_int.hpp"
#include "common/scratch.hpp"
#include "findmug/cloud/cloud.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug::tables_detail {

inline constexpr std::uint8_t kTableLabel = static_cast<std::uint8_t>(Label::Table);
inline constexpr std::uint8_t kFloorLabel = static_cast<std::uint8_t>(Label::Floor);
// Points further than this from the robot are corrupt, not far: no RGB-D
// sensor sees 100 m. Keeps voxel coordinates inside their 21-bit fields.
inline constexpr float kMaxPlausibleRangeM = 100.0f;
// Smallest clustering tolerance: below a millimetre voxel indices would
// overflow their fields at 100 m, and no depth sensor resolves it anyway.
inline constexpr float kMinToleranceM = 0.001f;

inline bool finitePoint(const Eigen::Vector3f& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

using detail::floorToInt;

// `value` with `precision` significant digits, for messages.
std::string fmt(double value, int precision = 3);

// Where the points of clusterPoints sit in an organized image, when they
// come from one: point k at pixel (*pixels)[k] (ascending) of an image
// `width` pixels wide, sampled every `stride` pixels of every `stride`-th
// row (so a point's grid neighbours are `stride` pixels left and `stride`
// rows up). Only a shortcut: the partition is the same with or without it.
struct PointGrid {
  const std::vector<int>* pixels = nullptr;
  int width = 0;
  int stride = 1;
};

// Exact Euclidean clustering (see euclideanClusterLabels in tables.hpp)
// without the input checks: the caller guarantees finite points within
// kMaxPlausibleRangeM and a tolerance of at least kMinToleranceM.
std::vector<int> clusterPoints(const std::vector<Eigen::Vector3f>& points, float tolerance,
                               const PointGrid& grid = {});
// The same into `labels` (resized; its capacity is reused frame to frame).
void clusterPointsInto(const std::vector<Eigen::Vector3f>& points, float tolerance,
                       const PointGrid& grid, std::vector<int>& labels);

struct ClusterOutcome {
  bool ok = false;
  std::string reason;  // why not
};

// Fills `table` (all but id, pixels, mean_confidence and search positions)
// from the cluster's points (or a sample of them): top height, centroid,
// axes, box, hull; point_count = `point_count`, the full cluster's size,
// which the reasons for a rejection also name.
ClusterOutcome describeCluster(const std::vector<Eigen::Vector3f>& points, int point_count,
                               const TableConfig& config, TableCluster& table);

// Step 1 of detectTables: the table-labelled pixels' points, in pixel order,
// that are finite and at a plausible table height and position (appended to
// `points`, their pixel indices to `pixels`); the others counted by reason
// in `result` (nonfinite_points, implausible_points; table_points counts
// those kept). Every pixel is taken (point stride 1). `simd` false: the
// portable loop even where the CPU has AVX2 (the tests compare the two).
void collectTablePoints(const OrganizedCloud& cloud, const LabelImage& labels,
                        const TableConfig& config, std::vector<Eigen::Vector3f>& points,
                        std::vector<int>& pixels, TableDetection& result, bool simd = true);

// Index of the cell holding (x, y) on a grid of cols x rows square cells of
// edge `cell` from (origin_x, origin_y), or -1 outside it. The reachability
// grid's cells (ReachabilityGrid::cellOf and the pass that builds it).
inline int gridCell(float x, float y, float origin_x, float origin_y, float cell, int cols,
                    int rows) {
  const int col = floorToInt((x - origin_x) / cell);
  const int row = floorToInt((y - origin_y) / cell);
  if (col < 0 || row < 0 || col >= cols || row >= rows) return -1;
  return row * cols + col;
}

// Observed floor cells and obstacle points around the search positions
// (`region`), from one pass over the labelled cloud; assess() flags a
// position unreachable with a reason (see tables.hpp, step 5).
class ReachabilityGrid {
 public:
  // `positions`: every position that assess() will be asked about.
  // `simd` false: the portable pass over the cloud even where the CPU has
  // AVX2 (the tests check that both build the same grid).
  ReachabilityGrid(const OrganizedCloud& cloud, const LabelImage& labels,
                   const Eigen::AlignedBox2f& region, const std::vector<Eigen::Vector2f>& positions,
                   const TableConfig& config, bool simd = true);
  void assess(SearchPosition& position) const;

  // What the pass over the cloud built, for the tests: per cell whether
  // floor was seen, and the obstacle points bucketed by cell (the points of
  // cell c are obstacle_points[obstacle_start[c] .. obstacle_start[c + 1])).
  const std::vector<std::uint8_t>& floorSeen() const { return *floor_seen_; }
  const std::vector<int>& obstacleStart() const { return *obstacle_start_; }
  const std::vector<Eigen::Vector2f>& obstaclePoints() const { return *obstacle_points_; }

 private:
  // Cells (clamped to the grid) within robot_radius_m of `q` on each axis.
  struct Window {
    int c0 = 0, c1 = -1, r0 = 0, r1 = -1;
  };
  Window windowOf(const Eigen::Vector2f& q) const;
  int cellOf(const Eigen::Vector2f& xy) const {
    return gridCell(xy.x(), xy.y(), origin_.x(), origin_.y(), cell_, cols_, rows_);
  }

  // This thread's buffers from earlier frames (scratch.hpp), borrowed for
  // the grid's lifetime.
  struct Buffers {
    std::vector<std::uint8_t> floor_seen, in_window;
    std::vector<int> obstacle_start, fill;
    std::vector<Eigen::Vector2f> obstacle_points;
    std::vector<std::pair<int, Eigen::Vector2f>> obstacles;
  };
  static Buffers& threadBuffers();

  const TableConfig& config_;
  Eigen::Vector2f origin_;
  float cell_;
  int cols_ = 0, rows_ = 0;
  detail::Borrowed<std::vector<std::uint8_t>> floor_seen_{threadBuffers().floor_seen};
  detail::Borrowed<std::vector<int>> obstacle_start_{threadBuffers().obstacle_start};
  detail::Borrowed<std::vector<Eigen::Vector2f>> obstacle_points_{threadBuffers().obstacle_points};
};

// The table-top test (table_top.cpp). flatShare: over the members within `band` of the top
// height whose normal is within the horizontal tilt of vertical, the share within the flat
// tilt (NaN when none is horizontal). softTop: whether a described cluster's top is large
// and not flat (TableConfig::min_flat_share), setting table.flat_share when measured.
float flatShare(const int* member, int n, const int* full_pixels, const OrganizedCloud& cloud,
                const NormalImage& normals, float top_height, float band, float cos_horizontal,
                float cos_flat);
bool softTop(const int* member, int n, const int* full_pixels, const OrganizedCloud& cloud,
             const NormalImage* normals, const TableConfig& config, TableCluster& table);

}  // namespace findmug::tables_detail
