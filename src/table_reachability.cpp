// table_reachability.cpp — whether the robot can stand at a search position.
//
// Reachability: the grid of observed floor and the buckets of obstacle
// points are built only over the region around the search positions, in one
// pass over the cloud.
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "tables_internal.hpp"

namespace findmug {

using namespace tables_detail;

ReachabilityGrid::ReachabilityGrid(const OrganizedCloud& cloud, const LabelImage& labels,
                 const Eigen::AlignedBox2f& region, const TableConfig& config)
    : config_(config), origin_(region.min()), cell_(config.floor_cell_m) {
  const Eigen::Vector2f size = region.sizes();
  cols_ = static_cast<int>(size.x() / cell_) + 1;
  rows_ = static_cast<int>(size.y() / cell_) + 1;
  const std::size_t cells = static_cast<std::size_t>(cols_) * rows_;
  floor_seen_.assign(cells, 0);
  obstacle_start_.assign(cells + 1, 0);

  std::vector<std::pair<int, Eigen::Vector2f>> obstacles;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!finitePoint(p)) continue;
    const int c = cellOf(p.head<2>());
    if (c < 0) continue;
    const std::uint8_t label = labels.labels[i];
    if (label == kFloorLabel) {
      if (std::abs(p.z()) <= config.floor_tolerance_m) floor_seen_[c] = 1;
    } else if (p.z() >= config.obstacle_min_height_m && p.z() <= config.robot_height_m) {
      obstacles.emplace_back(c, p.head<2>());
    }
  }
  for (const auto& [c, xy] : obstacles) ++obstacle_start_[c + 1];
  for (std::size_t c = 0; c < cells; ++c) obstacle_start_[c + 1] += obstacle_start_[c];
  obstacle_points_.resize(obstacles.size());
  std::vector<int> fill(obstacle_start_.begin(), obstacle_start_.end() - 1);
  for (const auto& [c, xy] : obstacles) obstacle_points_[fill[c]++] = xy;
}

void ReachabilityGrid::assess(SearchPosition& position) const {
  const float r = config_.robot_radius_m;
  const Eigen::Vector2f& q = position.xy;
  int footprint = 0, seen = 0, obstacle_count = 0;
  const int c0 = static_cast<int>(std::floor((q.x() - r - origin_.x()) / cell_));
  const int c1 = static_cast<int>(std::floor((q.x() + r - origin_.x()) / cell_));
  const int r0 = static_cast<int>(std::floor((q.y() - r - origin_.y()) / cell_));
  const int r1 = static_cast<int>(std::floor((q.y() + r - origin_.y()) / cell_));
  const int own = cellOf(q);
  for (int row = std::max(0, r0); row <= std::min(rows_ - 1, r1); ++row) {
    for (int col = std::max(0, c0); col <= std::min(cols_ - 1, c1); ++col) {
      const int c = row * cols_ + col;
      const Eigen::Vector2f centre =
          origin_ + Eigen::Vector2f((col + 0.5f) * cell_, (row + 0.5f) * cell_);
      // Footprint: cells whose centre is under the robot, and always the
      // cell of the position itself (for radii below half a cell).
      if ((centre - q).norm() <= r || c == own) {
        ++footprint;
        seen += floor_seen_[c];
      }
      for (int k = obstacle_start_[c]; k < obstacle_start_[c + 1]; ++k) {
        if ((obstacle_points_[k] - q).squaredNorm() <= r * r) ++obstacle_count;
      }
    }
  }
  std::string reason;
  if (obstacle_count >= config_.obstacle_min_points) {
    reason = "obstacle within robot radius (" + std::to_string(obstacle_count) + " points)";
  }
  const float seen_fraction = footprint > 0 ? static_cast<float>(seen) / footprint : 0.0f;
  if (seen_fraction < config_.min_floor_observed_fraction) {
    if (!reason.empty()) reason += "; ";
    reason += "no observed floor (" + std::to_string(static_cast<int>(100.0f * seen_fraction)) +
              " % of the footprint seen)";
  }
  position.reachable = reason.empty();
  position.reason = reason;
}

}  // namespace findmug
