// findmug/map/table_top_views.hpp — which parts of the mapped table tops the camera has
// shown from near enough to recognise an object standing on them.
//
// Why: a robot searching table tops for an object need not drive to every table. A top
// that the camera already showed whole (while driving, turning or looking around), from
// within the reach of the robot's recogniser and not hidden behind something, has been
// searched: an object on it would have been in view. Sending the robot only to the tops
// not yet seen that way is what makes a table-first search quick (BENCHMARKS.md §7).
//
// The memory is a set of floor-plane cells (`cell_m` on a side, map frame x, y) of table
// top that some view showed. A cell of a table's top (its hull sampled at cell centres, at
// the top's height) counts as shown by a view when
//   * it lies within `range_m` of the camera (3-D distance) and in front of it,
//   * it projects inside the image, at least `border_px` from the edge, and
//   * the depth measured at that pixel is valid and not nearer than the cell by more than
//     `occlusion_m` (nearer means something stands in front of it; an object on the top is
//     within that margin of it and does not hide the top).
// A table's seen share is the share of its hull's cells in the set. The set is keyed by
// place, not by table id, so a table the map merges or renumbers keeps what was seen of it.
//
// Pure core code: no LCM, no clock, no threads.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <unordered_set>
#include <vector>

#include "findmug/frame/frame.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {

struct TableTopViewsConfig {
  float range_m = 2.0f;       // the recogniser's reach: farther cells are not searched by a view
  float cell_m = 0.05f;       // grid of the memory and of the tops' samples
  float occlusion_m = 0.15f;  // measured depth this much nearer than a cell hides it
  int border_px = 8;          // cells projecting nearer the image edge do not count
};

// Throws findmug::Error naming the field when a value is out of range.
void validateTableTopViewsConfig(const TableTopViewsConfig& config);

class TableTopViews {
 public:
  explicit TableTopViews(TableTopViewsConfig config = {});

  // Records the cells of the tables' tops (map frame: hull, top_height above the map
  // floor) that the depth image of `frame` shows from `camera_in_map` (camera frame: x
  // right, y down, z forward). Returns how many cells were new.
  int observe(const std::vector<TableCluster>& map_tables, const RgbdFrame& frame,
              const Eigen::Isometry3d& camera_in_map);

  // Share (0..1) of the table's top cells that some view showed; 0 without a hull.
  double seenShare(const TableCluster& table) const;

  std::size_t cells() const { return seen_.size(); }
  void clear() { seen_.clear(); }
  const TableTopViewsConfig& config() const { return config_; }

 private:
  std::uint64_t key(int ix, int iy) const;
  // Calls f(ix, iy, x, y) for each grid cell whose centre lies inside the table's hull.
  template <class F>
  void forEachTopCell(const TableCluster& table, F&& f) const;

  TableTopViewsConfig config_;
  std::unordered_set<std::uint64_t> seen_;
};

}  // namespace findmug
