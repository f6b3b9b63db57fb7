// findmug/map/table_map.hpp — a small persistent semantic map of tables.
//
// findTables (tables.hpp) sees one frame in the robot base frame. With the
// robot's pose in a map frame (2-D: the base frame is ground aligned, so the
// pose is x, y, yaw on the floor, as in the LCM type robot_pose_t), tables
// can be placed in the map and tracked across frames:
//
//   * transformTable(): one frame's tables (centroid, axes, box, hull,
//     search positions) in the map frame;
//   * TableMap::update(): merges a frame's tables into a list with stable ids.
//     An observation joins a mapped table when their footprints (convex
//     hulls on the floor) overlap or come within `match_gap_m` and their top
//     heights agree within `match_height_m`; otherwise it starts a new,
//     tentative table. A table is confirmed after `confirm_sightings`
//     sightings, and forgotten after `forget_misses` consecutive updates in
//     which it was expected (its box centre inside the camera's view: range
//     and bearing from the pose) but not seen. Given the frame's depth image
//     (a DepthView), an update counts a miss only when the depth image shows
//     the table's top, or what lies beyond it, at more of its sample points
//     than it shows something nearer (by `hidden_margin_m`) in front of them:
//     a table behind a wall or a cabinet is not missing, it is out of sight.
//     A tentative table that is not confirmed within `tentative_timeout_s` is
//     dropped as well.
//   * The geometry of a mapped table comes from its last `max_observations`
//     observations: the hull is the hull of their hulls (so partial views of
//     one table add up to the whole top), the axes are the principal axes of
//     that hull's area, the top height their mean. Search positions are
//     recomputed from it (computeSearchPositions); each takes the
//     reachability of the newest observed position within
//     `position_match_m`, and is unreachable ("not observed yet") when no
//     observation ever evaluated that spot.
//
// Pure core code: no LCM, no clock, no threads; the caller passes the time.
// Call update() only for frames that were labelled (a frame without a
// ground plane is no evidence that a table is gone).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "findmug/common/pose2d.hpp"
#include "findmug/map/depth_view.hpp"
#include "findmug/settings/settings.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {


// All geometry of `table` (centroid x,y, axes, centre, hull, search
// positions with their yaw) moved by `pose`: with pose = base in map, base
// frame -> map frame; with inversePose(pose), map frame -> base frame.
// Heights, extents, counts and reachability are unchanged.
TableCluster transformTable(const TableCluster& table, const Pose2D& pose);

struct TableMapConfig {
  int confirm_sightings = 3;          // sightings (updates with a match) to confirm a table
  int forget_misses = 3;              // consecutive expected-but-unseen updates to forget it
  double tentative_timeout_s = 10.0;  // unconfirmed tables older than this are dropped
  float match_gap_m = 0.15f;          // footprints this close (or overlapping) may be one table
  float match_height_m = 0.15f;       // ... when their top heights differ by at most this
  // The camera's view on the floor, from the base frame origin along +x:
  // a mapped table is expected in a frame when its box centre is within
  // this range and bearing. Defaults: Kinect-like 57° field of view less a
  // margin, and the range where tables are reliably labelled.
  float view_half_angle_rad = 0.4f;
  float view_min_range_m = 0.8f;
  float view_max_range_m = 4.0f;
  // With a depth image: measured depth this much nearer than a point of a
  // mapped table's top means something stands in front of it (not a miss).
  float hidden_margin_m = 0.3f;
  int max_observations = 10;      // newest observations kept per table
  float position_match_m = 0.3f;  // observed position near a recomputed one lends its verdict
};

// Throws findmug::Error naming the setting (as `table_map.KEY`) when out of range.
void validateTableMapConfig(const TableMapConfig& config);

// The `table_map:` section of the config file, one key per field above. Its
// ranges only keep single numbers sane; validateTableMapConfig has the final
// word on consistency (a program binds it with it: SettingsSchema::bind).
const SettingsTable<TableMapConfig>& tableMapSettings();

struct MappedTable {
  TableCluster table;  // map frame; table.id is the stable id (1, 2, ...; never reused)
  int sightings = 0;
  int misses = 0;  // consecutive updates in which it was expected but not seen
  bool confirmed = false;
  std::uint64_t first_seen_utime = 0;
  std::uint64_t last_seen_utime = 0;
};

struct TableMapUpdate {
  // For each input table (same order): the stable id it was merged into.
  std::vector<int> assigned_ids;
  std::vector<int> created;    // new (tentative) tables
  std::vector<int> confirmed;  // tables that reached confirm_sightings in this update
  std::vector<int> forgotten;  // tables removed in this update (missed, timed out, merged)
  std::vector<std::string> diagnostics;  // why tables were forgotten or merged, for the log
};

class TableMap {
 public:
  explicit TableMap(TableMapConfig map_config = {}, TableConfig table_config = {});

  // Merges one labelled frame's tables (base frame, as from findTables)
  // seen from `base_in_map` at `utime` (microseconds). `view` (optional) is
  // the frame's depth image with its camera pose in the map: without it, a
  // table expected in view and not seen is missed even when something hid
  // it. Throws findmug::Error on a non-finite pose or an update older than
  // the last.
  TableMapUpdate update(const std::vector<TableCluster>& tables_base, const Pose2D& base_in_map,
                        std::uint64_t utime, const DepthView* view = nullptr);

  // Every table in the map, tentative ones included, by id.
  const std::vector<MappedTable>& tables() const { return tables_; }
  // The confirmed tables only (map frame), by id: what a navigation client plans on.
  std::vector<TableCluster> confirmedTables() const;
  void clear();

  const TableMapConfig& config() const { return map_config_; }

 private:
  void rebuild(std::size_t index);
  bool expectedInView(const TableCluster& table, const Pose2D& base_in_map) const;
  // Whether `view` shows the table's top (or beyond it) at more sample points than it
  // shows something in front of them.
  bool topInSight(const TableCluster& table, const DepthView& view) const;

  TableMapConfig map_config_;
  TableConfig table_config_;
  std::vector<MappedTable> tables_;
  struct Observation {
    std::uint64_t utime = 0;
    TableCluster table;  // map frame
  };
  std::vector<std::deque<Observation>> observations_;  // per table, oldest first
  int next_id_ = 1;
  std::uint64_t last_utime_ = 0;
};

// Polygon helpers (convex, counter-clockwise), exposed for tests.
float polygonArea(const std::vector<Eigen::Vector2f>& polygon);
std::vector<Eigen::Vector2f> intersectConvex(const std::vector<Eigen::Vector2f>& a,
                                             const std::vector<Eigen::Vector2f>& b);
// Smallest distance between two convex polygons, 0 when they overlap.
float convexGap(const std::vector<Eigen::Vector2f>& a, const std::vector<Eigen::Vector2f>& b);

}  // namespace findmug
