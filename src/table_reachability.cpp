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

ReachabilityGrid::Buffers& ReachabilityGrid::threadBuffers() {
  thread_local Buffers buffers;
  return buffers;
}

ReachabilityGrid::ReachabilityGrid(const OrganizedCloud& cloud, const LabelImage& labels,
                                   const Eigen::AlignedBox2f& region,
                                   const std::vector<Eigen::Vector2f>& positions,
                                   const TableConfig& config)
    : config_(config), origin_(region.min()), cell_(config.floor_cell_m) {
  const Eigen::Vector2f size = region.sizes();
  cols_ = static_cast<int>(size.x() / cell_) + 1;
  rows_ = static_cast<int>(size.y() / cell_) + 1;
  const std::size_t cells = static_cast<std::size_t>(cols_) * rows_;
  std::vector<std::uint8_t>& floor_seen = *floor_seen_;
  std::vector<int>& obstacle_start = *obstacle_start_;
  std::vector<Eigen::Vector2f>& obstacle_points = *obstacle_points_;
  floor_seen.assign(cells, 0);
  obstacle_start.assign(cells + 1, 0);
  // Cells that assess() reads obstacles from (the window around each
  // position). The region also holds the table itself, whose points are at
  // obstacle height: they are kept only where a robot could stand.
  detail::Borrowed in_window_buffer(threadBuffers().in_window);
  std::vector<std::uint8_t>& in_window = *in_window_buffer;
  in_window.assign(cells, 0);
  for (const Eigen::Vector2f& q : positions) {
    const Window w = windowOf(q);
    for (int row = w.r0; row <= w.r1; ++row) {
      for (int col = w.c0; col <= w.c1; ++col) in_window[row * cols_ + col] = 1;
    }
  }

  // Most of the frame lies outside the region: a plain comparison with a box
  // one cell larger than the grid rejects those points before cellOf's
  // divisions (and rejects NaN and infinite x, y; a NaN or infinite z fails
  // both the floor and the obstacle test below).
  const float x_min = origin_.x(), y_min = origin_.y();
  const float x_max = origin_.x() + static_cast<float>(cols_ + 1) * cell_;
  const float y_max = origin_.y() + static_cast<float>(rows_ + 1) * cell_;
  detail::Borrowed obstacles_buffer(threadBuffers().obstacles);
  std::vector<std::pair<int, Eigen::Vector2f>>& obstacles = *obstacles_buffer;
  obstacles.clear();
  // A point counts only as observed floor (floor label, at floor height) or
  // as an obstacle (any other label, between obstacle_min_height_m and
  // robot_height_m); its cell is worked out only then. (A vectorised pass
  // over every pixel was tried and was slower: most pixels fail the box test
  // above, which a predicted branch rejects more cheaply.)
  const float floor_tolerance = config.floor_tolerance_m;
  const float obstacle_low = config.obstacle_min_height_m, obstacle_high = config.robot_height_m;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!(p.x() >= x_min && p.x() <= x_max && p.y() >= y_min && p.y() <= y_max)) continue;
    const bool floor_label = labels.labels[i] == kFloorLabel;
    const bool floor = floor_label && std::abs(p.z()) <= floor_tolerance;
    const bool obstacle = !floor_label && p.z() >= obstacle_low && p.z() <= obstacle_high;
    if (!floor && !obstacle) continue;
    const int c = cellOf(p.head<2>());
    if (c < 0) continue;
    if (floor) {
      floor_seen[c] = 1;
    } else if (in_window[c]) {
      obstacles.emplace_back(c, p.head<2>());
    }
  }
  for (const auto& [c, xy] : obstacles) ++obstacle_start[c + 1];
  for (std::size_t c = 0; c < cells; ++c) obstacle_start[c + 1] += obstacle_start[c];
  obstacle_points.resize(obstacles.size());
  detail::Borrowed fill_buffer(threadBuffers().fill);
  std::vector<int>& fill = *fill_buffer;
  fill.assign(obstacle_start.begin(), obstacle_start.end() - 1);
  for (const auto& [c, xy] : obstacles) obstacle_points[fill[c]++] = xy;
}

void ReachabilityGrid::assess(SearchPosition& position) const {
  const float r = config_.robot_radius_m;
  const Eigen::Vector2f& q = position.xy;
  int footprint = 0, seen = 0, obstacle_count = 0;
  const Window w = windowOf(q);
  const int own = cellOf(q);
  const std::vector<std::uint8_t>& floor_seen = *floor_seen_;
  const std::vector<int>& obstacle_start = *obstacle_start_;
  const std::vector<Eigen::Vector2f>& obstacle_points = *obstacle_points_;
  for (int row = w.r0; row <= w.r1; ++row) {
    for (int col = w.c0; col <= w.c1; ++col) {
      const int c = row * cols_ + col;
      const Eigen::Vector2f centre =
          origin_ + Eigen::Vector2f((col + 0.5f) * cell_, (row + 0.5f) * cell_);
      // Footprint: cells whose centre is under the robot, and always the
      // cell of the position itself (for radii below half a cell).
      if ((centre - q).norm() <= r || c == own) {
        ++footprint;
        seen += floor_seen[c];
      }
      for (int k = obstacle_start[c]; k < obstacle_start[c + 1]; ++k) {
        if ((obstacle_points[k] - q).squaredNorm() <= r * r) ++obstacle_count;
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

ReachabilityGrid::Window ReachabilityGrid::windowOf(const Eigen::Vector2f& q) const {
  const float r = config_.robot_radius_m;
  Window w;
  w.c0 = std::max(0, static_cast<int>(std::floor((q.x() - r - origin_.x()) / cell_)));
  w.c1 = std::min(cols_ - 1, static_cast<int>(std::floor((q.x() + r - origin_.x()) / cell_)));
  w.r0 = std::max(0, static_cast<int>(std::floor((q.y() - r - origin_.y()) / cell_)));
  w.r1 = std::min(rows_ - 1, static_cast<int>(std::floor((q.y() + r - origin_.y()) / cell_)));
  return w;
}

}  // namespace findmug
