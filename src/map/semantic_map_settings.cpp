// semantic_map_settings.cpp — the semantic_map.* settings and their checks (see semantic_map.hpp).
#include <cmath>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/map/semantic_map.hpp"
#include "semantic_map_internal.hpp"

namespace findmug {

using namespace semantic_map_detail;

// ---- settings ------------------------------------------------------------------------------

void validateSemanticMapConfig(const SemanticMapConfig& c) {
  auto positive = [](const char* key, float v) {
    if (!std::isfinite(v) || v <= 0.0f) badSetting(key, v, "must be a positive number");
  };
  if (!std::isfinite(c.voxel_size_m) || c.voxel_size_m < 0.01f || c.voxel_size_m > 1.0f) {
    badSetting("voxel_size_m", c.voxel_size_m, "must be in [0.01, 1] m");
  }
  if (c.pixel_stride < 1 || c.pixel_stride > 16) {
    badSetting("pixel_stride", c.pixel_stride, "must be in [1, 16]");
  }
  if (c.carve_stride < 1 || c.carve_stride > 64) {
    badSetting("carve_stride", c.carve_stride, "must be in [1, 64]");
  }
  positive("max_range_m", c.max_range_m);
  if (c.max_range_m > 100.0f) badSetting("max_range_m", c.max_range_m, "must be at most 100 m");
  if (!std::isfinite(c.carve_margin_m) || c.carve_margin_m < 0.0f) {
    badSetting("carve_margin_m", c.carve_margin_m, "must be a number >= 0");
  }
  positive("hit_logodds", c.hit_logodds);
  positive("miss_logodds", c.miss_logodds);
  positive("max_logodds", c.max_logodds);
  if (!std::isfinite(c.seen_through_logodds) || c.seen_through_logodds < 0.0f ||
      c.seen_through_logodds > 125.0f) {
    badSetting("seen_through_logodds", c.seen_through_logodds, "must be in [0, 125] (0: off)");
  }
  if (c.max_logodds * SemanticMap::kLogOddsScale > 32000.0f) {
    badSetting("max_logodds", c.max_logodds, "must be at most 125");
  }
  if (c.hit_logodds > c.max_logodds) {
    badSetting("hit_logodds", c.hit_logodds,
               "must not be above semantic_map.max_logodds (" + fmt(c.max_logodds) + ")");
  }
  if (c.max_voxels < 1000) badSetting("max_voxels", c.max_voxels, "must be >= 1000");
  if (c.min_table_voxels < 1) badSetting("min_table_voxels", c.min_table_voxels, "must be >= 1");
  if (c.min_voxel_frames < 1) badSetting("min_voxel_frames", c.min_voxel_frames, "must be >= 1");
  if (!std::isfinite(c.table_match_gap_m) || c.table_match_gap_m < 0.0f) {
    badSetting("table_match_gap_m", c.table_match_gap_m, "must be a number >= 0");
  }
  if (c.support_frames < 1) badSetting("support_frames", c.support_frames, "must be >= 1");
  if (c.support_min_voxels < 1) {
    badSetting("support_min_voxels", c.support_min_voxels, "must be >= 1");
  }
  positive("viewpoint_cell_m", c.viewpoint_cell_m);
  if (!std::isfinite(c.viewpoint_angle_deg) || c.viewpoint_angle_deg <= 0.0f ||
      c.viewpoint_angle_deg > 360.0f) {
    badSetting("viewpoint_angle_deg", c.viewpoint_angle_deg, "must be in (0, 360]");
  }
}

const SettingsTable<SemanticMapConfig>& semanticMapSettings() {
  using M = SemanticMapConfig;
  static const SettingsTable<M> table = [] {
    SettingsTable<M> t("semantic_map");
    t.add(numberSetting<M, float>(
        "semantic_map.voxel_size_m", [](M& m) -> float& { return m.voxel_size_m; }, 0.01, 1,
        "edge of a map voxel"));
    t.add(integerSetting<M, int>(
        "semantic_map.pixel_stride", [](M& m) -> int& { return m.pixel_stride; }, 1, 16,
        "every n-th pixel of every n-th row is fused"));
    t.add(integerSetting<M, int>(
        "semantic_map.carve_stride", [](M& m) -> int& { return m.carve_stride; }, 1, 64,
        "every n-th pixel of every n-th row casts a free-space ray"));
    t.add(numberSetting<M, float>(
        "semantic_map.max_range_m", [](M& m) -> float& { return m.max_range_m; }, 0.1, 100,
        "points farther from the camera are not fused (rays are cut here)"));
    t.add(numberSetting<M, float>(
        "semantic_map.carve_margin_m", [](M& m) -> float& { return m.carve_margin_m; }, 0, 10,
        "free-space rays stop this short of the measured point"));
    t.add(numberSetting<M, float>(
        "semantic_map.hit_logodds", [](M& m) -> float& { return m.hit_logodds; }, 0.01, 125,
        "occupancy log-odds a frame's hit adds to a voxel"));
    t.add(numberSetting<M, float>(
        "semantic_map.miss_logodds", [](M& m) -> float& { return m.miss_logodds; }, 0.01, 125,
        "occupancy log-odds a ray through a voxel takes away (0 or below: removed)"));
    t.add(numberSetting<M, float>(
        "semantic_map.max_logodds", [](M& m) -> float& { return m.max_logodds; }, 0.01, 125,
        "occupancy log-odds cap (how many misses a long-seen voxel survives)"));
    t.add(numberSetting<M, float>(
        "semantic_map.seen_through_logodds", [](M& m) -> float& { return m.seen_through_logodds; },
        0, 125, "log-odds a table-top voxel loses in a frame whose depth lies behind it (0: off)"));
    t.add(integerSetting<M, int>(
        "semantic_map.max_voxels", [](M& m) -> int& { return m.max_voxels; }, 1000, 100000000,
        "memory bound: oldest voxels dropped above it (about 64 bytes each)"));
    t.add(integerSetting<M, int>(
        "semantic_map.min_table_voxels", [](M& m) -> int& { return m.min_table_voxels; }, 1,
        10000000, "table voxels a table from the map needs"));
    t.add(integerSetting<M, int>(
        "semantic_map.min_voxel_frames", [](M& m) -> int& { return m.min_voxel_frames; }, 1, 65535,
        "frames a voxel must be seen in to count for tables"));
    t.add(numberSetting<M, float>(
        "semantic_map.table_match_gap_m", [](M& m) -> float& { return m.table_match_gap_m; }, 0, 5,
        "a map table this close to an earlier one keeps its id"));
    t.add(integerSetting<M, int>(
        "semantic_map.support_frames", [](M& m) -> int& { return m.support_frames; }, 1, 1000000,
        "newest frames whose table votes are kept to count a table's support"));
    t.add(integerSetting<M, int>(
        "semantic_map.support_min_voxels", [](M& m) -> int& { return m.support_min_voxels; }, 1,
        1000000, "table-voted voxels by which a frame supports a table"));
    t.add(numberSetting<M, float>(
        "semantic_map.viewpoint_cell_m", [](M& m) -> float& { return m.viewpoint_cell_m; }, 0.01,
        100, "viewpoints: camera positions in cells of this size ..."));
    t.add(numberSetting<M, float>(
        "semantic_map.viewpoint_angle_deg", [](M& m) -> float& { return m.viewpoint_angle_deg; }, 1,
        360, "... and headings in sectors of this angle"));
    return t;
  }();
  return table;
}

}  // namespace findmug
