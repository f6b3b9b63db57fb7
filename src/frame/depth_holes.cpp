#include "findmug/frame/depth_holes.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

// Fills the run of `length` pixels from `first`, `stride` apart, between the
// depths `before` and `after` (both > 0) as the header says.
void fillRun(std::uint16_t* first, int length, std::ptrdiff_t stride, double before, double after,
             const DepthHoleFillConfig& config) {
  const double farther = std::max(before, after);
  const bool smooth = std::abs(before - after) <= config.smooth_tolerance * farther;
  for (int k = 0; k < length; ++k) {
    const double t = static_cast<double>(k + 1) / static_cast<double>(length + 1);
    const double depth = smooth ? before + t * (after - before) : farther;
    first[k * stride] = static_cast<std::uint16_t>(std::lround(depth));
  }
}

// The row pass: the bounded runs of each row up to max_run_px. Returns how many
// pixels it filled.
std::size_t fillRows(std::uint16_t* depth, int width, int height,
                     const DepthHoleFillConfig& config) {
  std::size_t filled = 0;
  for (int y = 0; y < height; ++y) {
    std::uint16_t* row = depth + static_cast<std::ptrdiff_t>(y) * width;
    int x = 0;
    while (x < width) {
      if (row[x] != 0) {
        ++x;
        continue;
      }
      int end = x;
      while (end < width && row[end] == 0) ++end;
      const int length = end - x;
      if (x > 0 && end < width && length <= config.max_run_px) {
        fillRun(row + x, length, 1, row[x - 1], row[end], config);
        filled += static_cast<std::size_t>(length);
      }
      x = end;
    }
  }
  return filled;
}

// The column pass, reading the image in memory order with one open run per
// column (a strided walk down each column costs a cache line per pixel).
std::size_t fillColumns(std::uint16_t* depth, int width, int height,
                        const DepthHoleFillConfig& config) {
  thread_local std::vector<int> run_start;  // per column: the open run's first row, or -1
  run_start.assign(static_cast<std::size_t>(width), -1);
  std::size_t filled = 0;
  for (int y = 0; y < height; ++y) {
    std::uint16_t* row = depth + static_cast<std::ptrdiff_t>(y) * width;
    for (int x = 0; x < width; ++x) {
      int& start = run_start[static_cast<std::size_t>(x)];
      if (row[x] == 0) {
        if (start < 0) start = y;
      } else if (start >= 0) {
        const int length = y - start;
        if (start > 0 && length <= config.max_run_px) {
          std::uint16_t* first = depth + static_cast<std::ptrdiff_t>(start) * width + x;
          fillRun(first, length, width, first[-width], row[x], config);
          filled += static_cast<std::size_t>(length);
        }
        start = -1;
      }
    }
  }
  return filled;  // runs still open at the bottom touch the border: left empty
}

}  // namespace

void validateDepthHoleFillConfig(const DepthHoleFillConfig& config) {
  if (config.max_run_px < 0 || config.max_run_px > 10000) {
    throw Error("cloud.fill_depth_max_run_px must be 0..10000 (0 = off), got " +
                std::to_string(config.max_run_px));
  }
  if (!(config.smooth_tolerance >= 0.0f && config.smooth_tolerance <= 1.0f)) {
    throw Error("cloud.fill_depth_smooth_tolerance must be 0..1, got " +
                std::to_string(config.smooth_tolerance));
  }
}

std::size_t fillDepthHoles(std::vector<std::uint16_t>& depth_mm, int width, int height,
                           const DepthHoleFillConfig& config) {
  if (width < 0 || height < 0 ||
      depth_mm.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw Error("fillDepthHoles: depth image holds " + std::to_string(depth_mm.size()) +
                " pixels, not " + std::to_string(width) + " x " + std::to_string(height));
  }
  validateDepthHoleFillConfig(config);
  if (config.max_run_px == 0 || depth_mm.empty()) return 0;
  // Columns, then rows (the order measured): a gap under a horizontal edge is
  // short along its column, the shadow band beside a vertical edge (a table
  // leg, a door frame) is long along its column and short along its row.
  const std::size_t filled = fillColumns(depth_mm.data(), width, height, config);
  return filled + fillRows(depth_mm.data(), width, height, config);
}

}  // namespace findmug
