#include "findmug/frame/depth_holes.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

// Fills the runs of one line of `count` pixels starting at `first`, `stride`
// apart; returns how many pixels it filled.
std::size_t fillLine(std::uint16_t* first, int count, std::ptrdiff_t stride,
                     const DepthHoleFillConfig& config) {
  std::size_t filled = 0;
  int i = 0;
  while (i < count) {
    if (first[i * stride] != 0) {
      ++i;
      continue;
    }
    int end = i;
    while (end < count && first[end * stride] == 0) ++end;
    const int run = end - i;
    if (i > 0 && end < count && run <= config.max_run_px) {
      const double before = first[(i - 1) * stride];
      const double after = first[end * stride];
      const double farther = std::max(before, after);
      const bool smooth = std::abs(before - after) <= config.smooth_tolerance * farther;
      for (int k = i; k < end; ++k) {
        const double t = static_cast<double>(k - i + 1) / static_cast<double>(run + 1);
        const double depth = smooth ? before + t * (after - before) : farther;
        first[k * stride] = static_cast<std::uint16_t>(std::lround(depth));
      }
      filled += static_cast<std::size_t>(run);
    }
    i = end;
  }
  return filled;
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
  std::size_t filled = 0;
  // Columns, then rows (the order measured): a gap under a horizontal edge is
  // short along its column, the shadow band beside a vertical edge (a table
  // leg, a door frame) is long along its column and short along its row.
  for (int x = 0; x < width; ++x) filled += fillLine(depth_mm.data() + x, height, width, config);
  for (int y = 0; y < height; ++y) {
    filled += fillLine(depth_mm.data() + static_cast<std::ptrdiff_t>(y) * width, width, 1, config);
  }
  return filled;
}

}  // namespace findmug
