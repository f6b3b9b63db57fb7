// table_search_positions.cpp — where the robot stands to search a table
// (Wolf et al. 2014), from the table's oriented box; see
// computeSearchPositions in tables.hpp.
#include <algorithm>
#include <cmath>

#include "findmug/tables/tables.hpp"

namespace findmug {

std::vector<SearchPosition> computeSearchPositions(const TableCluster& table,
                                                   const TableConfig& config) {
  const float d = config.safety_distance_m;
  const float r = config.arm_reach_m;
  const float half_length = table.extents.x();
  const float half_width = table.extents.y();
  int per_side = 1;
  if (r > d) {
    // Half-length of the edge one position covers: up to the midline of the
    // top when the arm gets that far, else the edge strip.
    const float to_midline = d + half_width;
    const float h =
        r > to_midline ? std::sqrt(r * r - to_midline * to_midline) : std::sqrt(r * r - d * d);
    // Guard against absurd counts from a tiny reach margin.
    per_side = std::clamp(static_cast<int>(std::ceil(half_length / h - 1e-4f)), 1, 64);
  }
  std::vector<SearchPosition> positions;
  for (int side : {1, -1}) {
    const Eigen::Vector2f normal = table.minor_axis * static_cast<float>(side);
    const float yaw = std::atan2(-normal.y(), -normal.x());  // facing the table
    for (int k = 0; k < per_side; ++k) {
      SearchPosition p;
      p.side = side;
      p.along_m = half_length * (static_cast<float>(2 * k + 1) / per_side - 1.0f);
      p.xy = table.center + table.major_axis * p.along_m + normal * (half_width + d);
      p.yaw = yaw;
      positions.push_back(p);
    }
  }
  return positions;
}

}  // namespace findmug
