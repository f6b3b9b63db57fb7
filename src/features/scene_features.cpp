// Scene features: three summaries of the frame built in one pass over its
// points (height histogram, occupied height bins per ground cell, farthest
// point per image column band), then read per patch.
#include "findmug/features/scene_features.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "common/floor_to_int.hpp"
#include "common/point_extent.hpp"
#include "common/scratch.hpp"
#include "findmug/common/error.hpp"

namespace findmug {

namespace {

constexpr int kHeightBins = 64;          // one bit each in a cell's mask
constexpr float kHistogramStep = 0.01f;  // m, for the frame's top
constexpr float kTopPercentile = 0.98f;

float horizontalDistance(const Eigen::Vector3f& p, const Eigen::Vector3f& camera) {
  return std::hypot(p.x() - camera.x(), p.y() - camera.y());
}

// Share of bins [lo, hi) set in `mask`; 0 for an empty range.
float fill(std::uint64_t mask, int lo, int hi) {
  lo = std::clamp(lo, 0, kHeightBins);
  hi = std::clamp(hi, 0, kHeightBins);
  if (hi <= lo) return 0.0f;
  const int width = hi - lo;
  const std::uint64_t range = (width == 64 ? ~std::uint64_t{0} : ((std::uint64_t{1} << width) - 1))
                              << lo;
  return static_cast<float>(std::popcount(mask & range)) / static_cast<float>(width);
}

void checkSceneInputs(const OrganizedCloud& cloud_ground, const Oversegmentation& segmentation,
                      const SegmentFeatures& features, const SceneConfig& config) {
  const std::size_t pixels = segmentation.pixel_segment.size();
  if (cloud_ground.points.size() != pixels || cloud_ground.width != segmentation.width) {
    throw Error("computeSceneFeatures: grids disagree: segmentation has " + std::to_string(pixels) +
                " pixels, cloud " + std::to_string(cloud_ground.points.size()));
  }
  const std::size_t n = segmentation.segments.size();
  if (features.features.size() != n || features.centroids.size() != n) {
    throw Error("computeSceneFeatures: " + std::to_string(n) + " segments but features for " +
                std::to_string(features.features.size()));
  }
  if (!(config.cell_m >= 0.01f && config.cell_m <= 1.0f))
    throw Error("computeSceneFeatures: features.scene_cell_m = " + std::to_string(config.cell_m) +
                " is out of range (0.01..1)");
  if (config.band_px < 1)
    throw Error("computeSceneFeatures: features.scene_band_px = " + std::to_string(config.band_px) +
                " must be at least 1");
}

// The frame's top: the 98th percentile of the point heights, from their histogram.
float frameTop(const std::vector<std::uint32_t>& heights, std::size_t valid) {
  const auto target = static_cast<std::size_t>(kTopPercentile * static_cast<float>(valid));
  std::size_t seen = 0;
  for (std::size_t h = 0; h < heights.size(); ++h) {
    seen += heights[h];
    if (seen > target) return (static_cast<float>(h) + 0.5f) * kHistogramStep;
  }
  return 0.0f;
}

}  // namespace

std::vector<float> computeSceneFeatures(const OrganizedCloud& cloud_ground,
                                        const Oversegmentation& segmentation,
                                        const SegmentFeatures& features,
                                        const Eigen::Vector3f& camera_position,
                                        const SceneConfig& config) {
  std::vector<float> out;
  computeSceneFeaturesInto(cloud_ground, segmentation, features, camera_position, config, out);
  return out;
}

void computeSceneFeaturesInto(const OrganizedCloud& cloud_ground,
                              const Oversegmentation& segmentation, const SegmentFeatures& features,
                              const Eigen::Vector3f& camera_position, const SceneConfig& config,
                              std::vector<float>& out) {
  checkSceneInputs(cloud_ground, segmentation, features, config);
  const std::size_t pixels = segmentation.pixel_segment.size();
  const std::size_t n = segmentation.segments.size();
  out.assign(n * kSceneFeatureDim, 0.0f);
  if (n == 0) return;

  const int width = std::max(1, segmentation.width);
  const int bands = (width + config.band_px - 1) / config.band_px;

  // Extent of the valid points in the ground plane, for the cell grid.
  const detail::PointExtent extent = detail::pointExtent(cloud_ground.points);
  const float min_x = extent.min_x, min_y = extent.min_y;
  const float max_x = extent.max_x, max_y = extent.max_y, max_z = extent.max_z;
  if (!std::isfinite(min_x)) return;
  const float cell = config.cell_m;
  const int cols = static_cast<int>((max_x - min_x) / cell) + 1;
  const int rows = static_cast<int>((max_y - min_y) / cell) + 1;
  const float inv_cell = 1.0f / cell;
  auto cellOf = [&](float v, float lo, int count) {
    return std::clamp(static_cast<int>((v - lo) * inv_cell), 0, count - 1);
  };
  auto binOf = [&](float z) {
    return std::clamp(detail::floorToInt(z * inv_cell), 0, kHeightBins - 1);
  };

  // Working memory kept per thread between frames (scratch.hpp).
  thread_local std::vector<std::uint64_t> occupied_tls;
  thread_local std::vector<float> band_far_tls;
  thread_local std::vector<std::uint32_t> heights_tls;
  thread_local std::vector<int> first_column_tls, last_column_tls;
  detail::Borrowed occupied_buffer(occupied_tls);
  detail::Borrowed band_far_buffer(band_far_tls);
  detail::Borrowed heights_buffer(heights_tls);
  detail::Borrowed first_column_buffer(first_column_tls), last_column_buffer(last_column_tls);
  std::vector<std::uint64_t>& occupied = *occupied_buffer;
  occupied.assign(static_cast<std::size_t>(cols) * rows, 0);
  std::vector<float>& band_far = *band_far_buffer;
  band_far.assign(static_cast<std::size_t>(bands), 0.0f);
  const int histogram_bins =
      std::max(1, static_cast<int>(std::max(0.0f, max_z) / kHistogramStep) + 1);
  std::vector<std::uint32_t>& heights = *heights_buffer;
  heights.assign(static_cast<std::size_t>(histogram_bins), 0);
  // Squared distances in the loop (one square root per band afterwards), and
  // multiplications by reciprocals: this pass visits every valid point.
  // The image columns each patch spans, for its bands.
  std::vector<int>& first_column = *first_column_buffer;
  first_column.assign(n, width);
  std::vector<int>& last_column = *last_column_buffer;
  last_column.assign(n, -1);
  std::size_t valid = 0;
  const float inv_step = 1.0f / kHistogramStep;
  const std::size_t grid_rows = pixels / static_cast<std::size_t>(width);
  // Row by row, band by band: a band's farthest distance stays in a register
  // (a max through memory per pixel is a store-to-load chain), there is no
  // division per pixel, and a patch's column span is updated once per run
  // of its pixels rather than per pixel.
  for (std::size_t v = 0; v < grid_rows; ++v) {
    const std::size_t row = v * static_cast<std::size_t>(width);
    const int* row_segment = segmentation.pixel_segment.data() + row;
    const Eigen::Vector3f* row_point = cloud_ground.points.data() + row;
    int run_segment = -1, run_start = 0;
    const auto closeRun = [&](int end) {  // the run [run_start, end) of run_segment
      if (run_segment >= 0 && static_cast<std::size_t>(run_segment) < n) {
        first_column[run_segment] = std::min(first_column[run_segment], run_start);
        last_column[run_segment] = std::max(last_column[run_segment], end - 1);
      }
    };
    for (int band = 0, band_start = 0; band_start < width; ++band, band_start += config.band_px) {
      const int band_end = std::min(width, band_start + config.band_px);
      float far = band_far[static_cast<std::size_t>(band)];
      for (int u = band_start; u < band_end; ++u) {
        const int segment = row_segment[u];
        if (segment != run_segment) {
          closeRun(u);
          run_segment = segment;
          run_start = u;
        }
        const Eigen::Vector3f& p = row_point[u];
        if (!std::isfinite(p.z())) continue;
        ++valid;
        const int cx = cellOf(p.x(), min_x, cols), cy = cellOf(p.y(), min_y, rows);
        occupied[static_cast<std::size_t>(cy) * cols + cx] |= std::uint64_t{1} << binOf(p.z());
        const float dx = p.x() - camera_position.x(), dy = p.y() - camera_position.y();
        far = std::max(far, dx * dx + dy * dy);
        ++heights[std::clamp(static_cast<int>(p.z() * inv_step), 0, histogram_bins - 1)];
      }
      band_far[static_cast<std::size_t>(band)] = far;
    }
    closeRun(width);
  }
  for (float& far : band_far) far = std::sqrt(far);
  const float top = frameTop(heights, valid);
  const int top_bin = binOf(top) + 1;

  for (std::size_t s = 0; s < n; ++s) {
    const FeatureVector& f = features.features[s];
    const float min_height = f[4], max_height = f[5];
    const Eigen::Vector3f& c = features.centroids[s];
    float* row = out.data() + s * kSceneFeatureDim;
    row[0] = top - max_height;

    // Farthest point over the bands this patch's columns fall in.
    float far = 0.0f;
    if (last_column[s] >= 0) {
      for (int band = first_column[s] / config.band_px; band <= last_column[s] / config.band_px;
           ++band)
        far = std::max(far, band_far[static_cast<std::size_t>(band)]);
    }
    row[1] = far > 0.0f ? horizontalDistance(c, camera_position) / far : 1.0f;

    std::uint64_t around = 0;
    const int cx = cellOf(c.x(), min_x, cols), cy = cellOf(c.y(), min_y, rows);
    for (int y = std::max(0, cy - 1); y <= std::min(rows - 1, cy + 1); ++y)
      for (int x = std::max(0, cx - 1); x <= std::min(cols - 1, cx + 1); ++x)
        around |= occupied[static_cast<std::size_t>(y) * cols + x];
    // Bins strictly below the patch's lowest point and strictly above its
    // highest (the patch's own points lie in between).
    row[2] = fill(around, 0, binOf(min_height));
    row[3] = fill(around, binOf(max_height) + 1, top_bin);
  }
}

}  // namespace findmug
