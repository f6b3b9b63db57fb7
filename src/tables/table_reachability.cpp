// table_reachability.cpp — whether the robot can stand at a search position.
//
// Reachability: the grid of observed floor and the buckets of obstacle
// points are built only over the region around the search positions, in one
// pass over the cloud.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "common/cpu_features.hpp"
#include "common/simd_vec3.hpp"
#include "tables/tables_internal.hpp"

namespace findmug {

using namespace tables_detail;

namespace {

// What the pass over the cloud needs: the box that rejects most points, the
// grid, the height bands, and where the results go.
struct CloudPass {
  float origin_x, origin_y;  // the grid's corner, also the box's lower corner
  float x_max, y_max;        // the box's upper corner: the grid one cell larger
  float cell;
  int cols, rows;
  float floor_tolerance, obstacle_low, obstacle_high;
  std::uint8_t* floor_seen;
  const std::uint8_t* in_window;
  std::vector<std::pair<int, Eigen::Vector2f>>* obstacles;
};

// Points [begin, end): a point counts only as observed floor (floor label,
// at floor height) or as an obstacle (any other label, between
// obstacle_min_height_m and robot_height_m); its cell is worked out only
// then. Obstacles are kept only in cells that assess() reads (in_window).
void passPortable(const Eigen::Vector3f* points, const std::uint8_t* labels, std::size_t begin,
                  std::size_t end, const CloudPass& pass) {
  for (std::size_t i = begin; i < end; ++i) {
    const Eigen::Vector3f& p = points[i];
    if (!(p.x() >= pass.origin_x && p.x() <= pass.x_max && p.y() >= pass.origin_y &&
          p.y() <= pass.y_max)) {
      continue;
    }
    const bool floor_label = labels[i] == kFloorLabel;
    const bool floor = floor_label && std::abs(p.z()) <= pass.floor_tolerance;
    const bool obstacle = !floor_label && p.z() >= pass.obstacle_low && p.z() <= pass.obstacle_high;
    if (!floor && !obstacle) continue;
    const int c =
        gridCell(p.x(), p.y(), pass.origin_x, pass.origin_y, pass.cell, pass.cols, pass.rows);
    if (c < 0) continue;
    if (floor) {
      pass.floor_seen[c] = 1;
    } else if (pass.in_window[c]) {
      pass.obstacles->emplace_back(c, p.head<2>());
    }
  }
}

#ifdef FINDMUG_AVX2_DISPATCH
// passPortable eight points at a time, up to the last whole group of eight;
// returns where it stopped. The same comparisons, subtractions, divisions
// and floors per point, as lanes; the points that pass are then handled
// one by one in point order (so obstacles are listed in the same order).
// On a table-rich view most points lie inside the box, and the portable
// loop paid two divisions and a hard-to-predict branch for each.
__attribute__((target("avx2"))) std::size_t passAvx2(const Eigen::Vector3f* points,
                                                     const std::uint8_t* labels, std::size_t n,
                                                     const CloudPass& pass) {
  const __m256 origin_x = _mm256_set1_ps(pass.origin_x), x_max = _mm256_set1_ps(pass.x_max);
  const __m256 origin_y = _mm256_set1_ps(pass.origin_y), y_max = _mm256_set1_ps(pass.y_max);
  const __m256 cell = _mm256_set1_ps(pass.cell);
  const __m256 floor_tolerance = _mm256_set1_ps(pass.floor_tolerance);
  const __m256 obstacle_low = _mm256_set1_ps(pass.obstacle_low);
  const __m256 obstacle_high = _mm256_set1_ps(pass.obstacle_high);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256i floor_label = _mm256_set1_epi32(kFloorLabel);
  const __m256i cols = _mm256_set1_epi32(pass.cols), rows = _mm256_set1_epi32(pass.rows);
  const __m256i minus_one = _mm256_set1_epi32(-1);
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256 x, y, z;
    detail::loadVec3x8(points[i].data(), x, y, z);
    const __m256 in_box = _mm256_and_ps(
        _mm256_and_ps(_mm256_cmp_ps(x, origin_x, _CMP_GE_OQ), _mm256_cmp_ps(x, x_max, _CMP_LE_OQ)),
        _mm256_and_ps(_mm256_cmp_ps(y, origin_y, _CMP_GE_OQ), _mm256_cmp_ps(y, y_max, _CMP_LE_OQ)));
    if (_mm256_movemask_ps(in_box) == 0) continue;
    std::int64_t label_bytes;
    std::memcpy(&label_bytes, labels + i, sizeof label_bytes);
    const __m256 is_floor_label = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
        _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(label_bytes)), floor_label));
    const __m256 floor = _mm256_and_ps(
        is_floor_label, _mm256_cmp_ps(_mm256_and_ps(z, abs_mask), floor_tolerance, _CMP_LE_OQ));
    const __m256 in_band = _mm256_and_ps(_mm256_cmp_ps(z, obstacle_low, _CMP_GE_OQ),
                                         _mm256_cmp_ps(z, obstacle_high, _CMP_LE_OQ));
    const __m256 obstacle = _mm256_andnot_ps(is_floor_label, in_band);
    const int floor_lanes = _mm256_movemask_ps(_mm256_and_ps(in_box, floor));
    const int obstacle_lanes = _mm256_movemask_ps(_mm256_and_ps(in_box, obstacle));
    if ((floor_lanes | obstacle_lanes) == 0) continue;
    // gridCell as lanes. floorToInt: truncate, then one less where that
    // rounded up.
    const __m256 col_f = _mm256_div_ps(_mm256_sub_ps(x, origin_x), cell);
    const __m256 row_f = _mm256_div_ps(_mm256_sub_ps(y, origin_y), cell);
    __m256i col = _mm256_cvttps_epi32(col_f), row = _mm256_cvttps_epi32(row_f);
    col = _mm256_add_epi32(
        col, _mm256_castps_si256(_mm256_cmp_ps(_mm256_cvtepi32_ps(col), col_f, _CMP_GT_OQ)));
    row = _mm256_add_epi32(
        row, _mm256_castps_si256(_mm256_cmp_ps(_mm256_cvtepi32_ps(row), row_f, _CMP_GT_OQ)));
    // 0 <= col < cols and 0 <= row < rows.
    const __m256i inside = _mm256_and_si256(
        _mm256_and_si256(_mm256_cmpgt_epi32(col, minus_one), _mm256_cmpgt_epi32(cols, col)),
        _mm256_and_si256(_mm256_cmpgt_epi32(row, minus_one), _mm256_cmpgt_epi32(rows, row)));
    const int inside_lanes = _mm256_movemask_ps(_mm256_castsi256_ps(inside));
    alignas(32) int cells[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(cells),
                       _mm256_add_epi32(_mm256_mullo_epi32(row, cols), col));
    for (int lanes = floor_lanes & inside_lanes; lanes != 0; lanes &= lanes - 1) {
      pass.floor_seen[cells[__builtin_ctz(static_cast<unsigned>(lanes))]] = 1;
    }
    for (int lanes = obstacle_lanes & inside_lanes; lanes != 0; lanes &= lanes - 1) {
      const int j = __builtin_ctz(static_cast<unsigned>(lanes));
      if (pass.in_window[cells[j]]) pass.obstacles->emplace_back(cells[j], points[i + j].head<2>());
    }
  }
  return i;
}
#endif

}  // namespace

ReachabilityGrid::Buffers& ReachabilityGrid::threadBuffers() {
  thread_local Buffers buffers;
  return buffers;
}

ReachabilityGrid::ReachabilityGrid(const OrganizedCloud& cloud, const LabelImage& labels,
                                   const Eigen::AlignedBox2f& region,
                                   const std::vector<Eigen::Vector2f>& positions,
                                   const TableConfig& config, bool simd)
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
  // both the floor and the obstacle test).
  detail::Borrowed obstacles_buffer(threadBuffers().obstacles);
  std::vector<std::pair<int, Eigen::Vector2f>>& obstacles = *obstacles_buffer;
  obstacles.clear();
  CloudPass pass;
  pass.origin_x = origin_.x();
  pass.origin_y = origin_.y();
  pass.x_max = origin_.x() + static_cast<float>(cols_ + 1) * cell_;
  pass.y_max = origin_.y() + static_cast<float>(rows_ + 1) * cell_;
  pass.cell = cell_;
  pass.cols = cols_;
  pass.rows = rows_;
  pass.floor_tolerance = config.floor_tolerance_m;
  pass.obstacle_low = config.obstacle_min_height_m;
  pass.obstacle_high = config.robot_height_m;
  pass.floor_seen = floor_seen.data();
  pass.in_window = in_window.data();
  pass.obstacles = &obstacles;
  const std::size_t n = std::min(cloud.points.size(), labels.labels.size());
  std::size_t done = 0;
#ifdef FINDMUG_AVX2_DISPATCH
  if (simd && detail::cpuHasAvx2()) {
    done = passAvx2(cloud.points.data(), labels.labels.data(), n, pass);
  }
#else
  (void)simd;
#endif
  passPortable(cloud.points.data(), labels.labels.data(), done, n, pass);
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
