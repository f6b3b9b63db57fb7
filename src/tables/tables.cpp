// tables.cpp — detectTables: the table stage that ties the table files
// together (see tables.hpp for the steps): picks the table points, clusters
// them (table_clustering.cpp), describes each cluster (table_geometry.cpp),
// places search positions (table_search_positions.cpp) and assesses them
// (table_reachability.cpp); also the settings check.
#include "findmug/tables/tables.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <limits>
#include <numeric>
#include <sstream>
#include <string>

#include "common/cpu_features.hpp"
#include "findmug/common/error.hpp"
#include "common/int_runs.hpp"
#include "common/simd_vec3.hpp"
#include "tables/tables_internal.hpp"

namespace findmug {

using namespace tables_detail;

namespace {

[[noreturn]] void badSetting(const std::string& key, double value, const std::string& rule) {
  throw Error("tables." + key + " = " + fmt(value, 6) + ": " + rule);
}

void checkInputs(const OrganizedCloud& cloud, const LabelImage& labels) {
  const std::size_t pixels = static_cast<std::size_t>(std::max(cloud.width, 0)) *
                             static_cast<std::size_t>(std::max(cloud.height, 0));
  if (cloud.width < 0 || cloud.height < 0 || cloud.points.size() != pixels) {
    throw Error("findTables: cloud is " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height) + " but holds " + std::to_string(cloud.points.size()) +
                " points");
  }
  if (labels.width != cloud.width || labels.height != cloud.height ||
      labels.labels.size() != pixels) {
    throw Error("findTables: label image is " + std::to_string(labels.width) + "x" +
                std::to_string(labels.height) + " with " + std::to_string(labels.labels.size()) +
                " labels, cloud is " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height));
  }
  if (!labels.confidence.empty() && labels.confidence.size() != pixels) {
    throw Error("findTables: label image has " + std::to_string(labels.confidence.size()) +
                " confidence values for " + std::to_string(pixels) + " pixels");
  }
}

// Per cluster, over its member pixels: the sum of the label confidences (the
// member count when the labels carry none: ground truth counts as certain),
// and, with normals, how many have a finite normal and how many of those are
// within the tilt of vertical. One pass for both: the normals' pass on its
// own waited on memory, here it runs beside the confidence sum's additions
// (which keep their order, so the same sum).
struct MemberSums {
  double confidence = 0.0;
  int valid_normals = 0;
  int horizontal = 0;
};
__attribute__((noinline)) MemberSums memberSums(const int* member, int n, const int* full_pixels,
                                                const std::vector<float>& confidence,
                                                const NormalImage* normals, float cos_tilt) {
  const float* conf = confidence.empty() ? nullptr : confidence.data();
  const Eigen::Vector3f* normal = normals ? normals->normals.data() : nullptr;
  double confidence_sum = conf ? 0.0 : static_cast<double>(n);
  int valid = 0, horizontal = 0;
  for (int k = 0; k < n; ++k) {
    const std::size_t pixel = static_cast<std::size_t>(full_pixels[member[k]]);
    if (conf) confidence_sum += conf[pixel];
    if (normal) {
      const float nz = normal[pixel].z();
      const int finite = std::isfinite(nz) ? 1 : 0;
      valid += finite;
      horizontal += finite & (std::abs(nz) >= cos_tilt ? 1 : 0);
    }
  }
  return {confidence_sum, valid, horizontal};
}


// out[k] = values[index[k]] for k < n, where `index` ascends strictly (a
// cluster's members): whole stretches of consecutive indices are copied at
// once. A stretch is found by doubling and halving its length, as
// index[k + m] - index[k] == m exactly when the m indices after index[k]
// are consecutive. A table's members are mostly such stretches (its points
// in pixel order), which one copy moves faster than an index each.
template <typename T>
void gatherByIndex(const T* values, const int* index, int n, T* out) {
  for (int k = 0; k < n;) {
    // The stretch index[k .. k + len) is consecutive; try to double it.
    int len = 1;
    while (k + 2 * len <= n && index[k + 2 * len - 1] - index[k] == 2 * len - 1) len *= 2;
    // Then grow it by halving steps up to its end (or n).
    for (int step = len / 2; step > 0; step /= 2) {
      if (k + len + step <= n && index[k + len + step - 1] - index[k] == len + step - 1) {
        len += step;
      }
    }
    // (The halving steps add any length below len: the stretch's end is
    // found to the element.)
    std::copy(values + index[k], values + index[k] + len, out + k);
    k += len;
  }
}

// What step 1 does with a table-labelled point.
enum class TablePoint { kKept, kNonFinite, kImplausible };
TablePoint classifyTablePoint(const Eigen::Vector3f& p, const TableConfig& config) {
  if (!finitePoint(p)) return TablePoint::kNonFinite;
  if (p.z() < config.min_table_height_m || p.z() > config.max_table_height_m ||
      std::abs(p.x()) > kMaxPlausibleRangeM || std::abs(p.y()) > kMaxPlausibleRangeM) {
    return TablePoint::kImplausible;
  }
  return TablePoint::kKept;
}

// Where the run of table labels that starts at row[x] ends (the first
// other label, or width): sixteen labels at a time.
int tableRunEnd(const std::uint8_t* row, int x, int width) {
#if defined(__SSE2__)
  const __m128i table = _mm_set1_epi8(static_cast<char>(kTableLabel));
  for (; x + 16 <= width; x += 16) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
    const unsigned other =
        ~static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(v, table))) & 0xFFFFu;
    if (other != 0) return x + __builtin_ctz(other);
  }
#endif
  while (x < width && row[x] == kTableLabel) ++x;
  return x;
}

#ifdef FINDMUG_AVX2_DISPATCH
// Step 1 over pixels [begin, end) of one run of table labels, eight at a
// time: classifyTablePoint's comparisons as lanes (a lane is finite when
// |v| < inf on all three axes, false for NaN), the kept points appended in
// pixel order. Returns where it stopped (the caller does the last ones).
__attribute__((target("avx2"))) std::size_t collectRunAvx2(
    const Eigen::Vector3f* cloud_points, std::size_t begin, std::size_t end,
    const TableConfig& config, std::vector<Eigen::Vector3f>& points, std::vector<int>& pixels,
    TableDetection& result) {
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 z_min = _mm256_set1_ps(config.min_table_height_m);
  const __m256 z_max = _mm256_set1_ps(config.max_table_height_m);
  const __m256 range = _mm256_set1_ps(kMaxPlausibleRangeM);
  const __m256i lane_index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  std::size_t i = begin;
  for (; i + 8 <= end; i += 8) {
    __m256 x, y, z;
    detail::loadVec3x8(cloud_points[i].data(), x, y, z);
    const __m256 ax = _mm256_and_ps(x, abs_mask), ay = _mm256_and_ps(y, abs_mask);
    const __m256 finite = _mm256_and_ps(
        _mm256_and_ps(_mm256_cmp_ps(ax, inf, _CMP_LT_OQ), _mm256_cmp_ps(ay, inf, _CMP_LT_OQ)),
        _mm256_cmp_ps(_mm256_and_ps(z, abs_mask), inf, _CMP_LT_OQ));
    // For finite lanes, the negation of classifyTablePoint's rejection.
    const __m256 plausible = _mm256_and_ps(
        _mm256_and_ps(_mm256_cmp_ps(z, z_min, _CMP_GE_OQ), _mm256_cmp_ps(z, z_max, _CMP_LE_OQ)),
        _mm256_and_ps(_mm256_cmp_ps(ax, range, _CMP_LE_OQ), _mm256_cmp_ps(ay, range, _CMP_LE_OQ)));
    const unsigned finite_lanes = static_cast<unsigned>(_mm256_movemask_ps(finite));
    const unsigned kept_lanes =
        static_cast<unsigned>(_mm256_movemask_ps(_mm256_and_ps(finite, plausible)));
    result.nonfinite_points += 8 - __builtin_popcount(finite_lanes);
    result.implausible_points += __builtin_popcount(finite_lanes & ~kept_lanes);
    result.table_points += __builtin_popcount(kept_lanes);
    if (kept_lanes == 0xFFu) {  // the common case: all eight
      points.insert(points.end(), cloud_points + i, cloud_points + i + 8);
      alignas(32) int index[8];
      _mm256_store_si256(reinterpret_cast<__m256i*>(index),
                         _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(i)), lane_index));
      pixels.insert(pixels.end(), index, index + 8);
      continue;
    }
    for (unsigned lanes = kept_lanes; lanes != 0; lanes &= lanes - 1) {
      const std::size_t k = i + static_cast<std::size_t>(__builtin_ctz(lanes));
      points.push_back(cloud_points[k]);
      pixels.push_back(static_cast<int>(k));
    }
  }
  return i;
}
#endif

}  // namespace

void tables_detail::collectTablePoints(const OrganizedCloud& cloud, const LabelImage& labels,
                                       const TableConfig& config,
                                       std::vector<Eigen::Vector3f>& points,
                                       std::vector<int>& pixels, TableDetection& result,
                                       bool simd) {
  const int width = cloud.width, height = cloud.height;
#ifdef FINDMUG_AVX2_DISPATCH
  const bool avx2 = simd && detail::cpuHasAvx2();
#else
  (void)simd;
#endif
  for (int y = 0; y < height; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * width;
    const std::uint8_t* label_row = labels.labels.data() + row;
    for (int x = 0; x < width;) {
      // Most of a frame is not table: skip to the next table pixel with
      // memchr (vectorised) instead of a compare and branch per pixel.
      const void* next =
          std::memchr(label_row + x, kTableLabel, static_cast<std::size_t>(width - x));
      if (!next) break;
      x = static_cast<int>(static_cast<const std::uint8_t*>(next) - label_row);
      const int run_end = tableRunEnd(label_row, x, width);
      std::size_t i = row + static_cast<std::size_t>(x);
      const std::size_t end = row + static_cast<std::size_t>(run_end);
#ifdef FINDMUG_AVX2_DISPATCH
      if (avx2) i = collectRunAvx2(cloud.points.data(), i, end, config, points, pixels, result);
#endif
      for (; i < end; ++i) {
        switch (classifyTablePoint(cloud.points[i], config)) {
          case TablePoint::kNonFinite: ++result.nonfinite_points; break;
          case TablePoint::kImplausible: ++result.implausible_points; break;
          case TablePoint::kKept:
            ++result.table_points;
            points.push_back(cloud.points[i]);
            pixels.push_back(static_cast<int>(i));
            break;
        }
      }
      x = run_end;
    }
  }
}

std::string tables_detail::fmt(double value, int precision) {
  std::ostringstream out;
  out.precision(precision);
  out << value;
  return out.str();
}

void validateTableConfig(const TableConfig& c) {
  auto positive = [](const char* key, float v) {
    if (!std::isfinite(v) || v <= 0.0f) badSetting(key, v, "must be a positive number");
  };
  auto nonNegative = [](const char* key, float v) {
    if (!std::isfinite(v) || v < 0.0f) badSetting(key, v, "must be a number >= 0");
  };
  // `key` must be above the setting `lower_key`, whose value is `lower`.
  auto above = [](const char* key, float v, const char* lower_key, float lower) {
    if (v <= lower) {
      badSetting(key, v,
                 "must be above tables." + std::string(lower_key) + " (" + fmt(lower) + ")");
    }
  };
  if (!std::isfinite(c.cluster_tolerance_m) || c.cluster_tolerance_m < kMinToleranceM) {
    badSetting("cluster_tolerance_m", c.cluster_tolerance_m, "must be at least 0.001 m");
  }
  if (c.min_cluster_points < 1)
    badSetting("min_cluster_points", c.min_cluster_points, "must be >= 1");
  if (c.point_stride < 1 || c.point_stride > 8) {
    badSetting("point_stride", c.point_stride, "must be in [1, 8] pixels");
  }
  if (c.max_cluster_points < c.min_cluster_points) {
    badSetting("max_cluster_points", c.max_cluster_points,
               "must not be below tables.min_cluster_points (" +
                   std::to_string(c.min_cluster_points) + ")");
  }
  nonNegative("safety_distance_m", c.safety_distance_m);
  positive("arm_reach_m", c.arm_reach_m);
  nonNegative("robot_radius_m", c.robot_radius_m);
  nonNegative("min_table_height_m", c.min_table_height_m);
  positive("max_table_height_m", c.max_table_height_m);
  above("max_table_height_m", c.max_table_height_m, "min_table_height_m", c.min_table_height_m);
  positive("top_band_m", c.top_band_m);
  nonNegative("min_table_width_m", c.min_table_width_m);
  nonNegative("obstacle_min_height_m", c.obstacle_min_height_m);
  positive("robot_height_m", c.robot_height_m);
  above("robot_height_m", c.robot_height_m, "obstacle_min_height_m", c.obstacle_min_height_m);
  if (c.obstacle_min_points < 1) {
    badSetting("obstacle_min_points", c.obstacle_min_points, "must be >= 1");
  }
  nonNegative("floor_tolerance_m", c.floor_tolerance_m);
  positive("floor_cell_m", c.floor_cell_m);
  if (!std::isfinite(c.min_floor_observed_fraction) || c.min_floor_observed_fraction < 0.0f ||
      c.min_floor_observed_fraction > 1.0f) {
    badSetting("min_floor_observed_fraction", c.min_floor_observed_fraction, "must be in [0, 1]");
  }
  if (!std::isfinite(c.region_max_tilt_deg) || c.region_max_tilt_deg < 0.0f ||
      c.region_max_tilt_deg > 90.0f) {
    badSetting("region_max_tilt_deg", c.region_max_tilt_deg, "must be in [0, 90] degrees");
  }
  nonNegative("region_min_area_m2", c.region_min_area_m2);
  positive("table_weight", c.table_weight);
  nonNegative("min_top_area_m2", c.min_top_area_m2);
  if (!std::isfinite(c.min_confidence) || c.min_confidence < 0.0f || c.min_confidence > 1.0f) {
    badSetting("min_confidence", c.min_confidence, "must be in [0, 1]");
  }
  if (!std::isfinite(c.min_horizontal_share) || c.min_horizontal_share < 0.0f ||
      c.min_horizontal_share > 1.0f) {
    badSetting("min_horizontal_share", c.min_horizontal_share, "must be in [0, 1]");
  }
  if (!std::isfinite(c.horizontal_tilt_deg) || c.horizontal_tilt_deg < 0.0f ||
      c.horizontal_tilt_deg > 90.0f) {
    badSetting("horizontal_tilt_deg", c.horizontal_tilt_deg, "must be in [0, 90] degrees");
  }
  nonNegative("soft_top_min_area_m2", c.soft_top_min_area_m2);
  if (!std::isfinite(c.flat_tilt_deg) || c.flat_tilt_deg < 0.0f ||
      c.flat_tilt_deg > c.horizontal_tilt_deg) {
    badSetting(
        "flat_tilt_deg", c.flat_tilt_deg,
        "must be in [0, tables.horizontal_tilt_deg (" + fmt(c.horizontal_tilt_deg) + ")] degrees");
  }
  if (!std::isfinite(c.min_flat_share) || c.min_flat_share < 0.0f || c.min_flat_share > 1.0f) {
    badSetting("min_flat_share", c.min_flat_share, "must be in [0, 1]");
  }
}


TableDetection detectTables(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                            const TableConfig& config, const NormalImage* normals_ground) {
  TableDetection result;
  detectTablesInto(cloud_ground, labels, config, normals_ground, result);
  return result;
}

namespace {
// Spare tables whose vectors keep their capacity for the next frame's
// tables (detectTablesInto). A few: a frame has a handful of tables, and
// each spare may hold up to a frame's worth of pixel indices.
constexpr std::size_t kMaxSpareTables = 8;

// A default table that takes over `old`'s pixel list and hull, emptied.
// (Not its search positions: computeSearchPositions returns a new list.)
TableCluster reusedTable(TableCluster&& old) {
  TableCluster table;
  table.hull = std::move(old.hull);
  table.hull.clear();
  table.pixels = std::move(old.pixels);
  table.pixels.clear();
  return table;
}

// detectTablesInto's working buffers, kept per thread: the stage runs once
// per frame, and a stream of frames then reuses them.
struct DetectionScratch {
  std::vector<TableCluster> spare;  // at most kMaxSpareTables
  // Step 1: the sampled table points and their pixels; with a stride, also
  // every table point's pixel and the sample index per grid cell (or -1).
  std::vector<Eigen::Vector3f> points;
  std::vector<int> pixels, full_pixels, sample_at;
  // Step 2: the cluster of each sampled point and (with a stride) of each
  // table point; the members of each cluster, full and sampled.
  std::vector<int> cluster_of, full_cluster;
  std::vector<int> member_start, members, sample_start, sample_members, fill;
  // Step 3: the sampled points of the cluster being described.
  std::vector<Eigen::Vector3f> cluster_points;
  // Step 5: where each search position is (the reachability grid is built
  // around them).
  std::vector<Eigen::Vector2f> position_xy;
};

// The earlier frame's tables become spares; the rest of `result` is reset.
void resetDetection(TableDetection& result, std::vector<TableCluster>& spare) {
  for (TableCluster& old : result.tables) {
    if (spare.size() < kMaxSpareTables) spare.push_back(std::move(old));
  }
  result.tables.clear();
  result.diagnostics.clear();
  result.table_points = result.nonfinite_points = result.implausible_points = 0;
  result.clusters_rejected = result.unsampled_points = 0;
  result.soft_tops = 0;
  result.soft_top_pixels.clear();
}

// A spare's buffers for the next table (a new table when none is left).
TableCluster takeSpareTable(std::vector<TableCluster>& spare) {
  if (spare.empty()) return TableCluster{};
  TableCluster table = reusedTable(std::move(spare.back()));
  spare.pop_back();
  return table;
}

void checkNormals(const OrganizedCloud& cloud_ground, const NormalImage* normals_ground) {
  if (normals_ground && !cloud_ground.points.empty() &&
      normals_ground->normals.size() != cloud_ground.points.size()) {
    throw Error("findTables: " + std::to_string(normals_ground->normals.size()) +
                " normals for a cloud of " + std::to_string(cloud_ground.points.size()) +
                " points");
  }
}

// The sample grid of tables.point_stride: cell (gx, gy) holds pixel
// (gx * stride, gy * stride).
struct SampleGrid {
  int stride = 1;
  int width = 0, height = 0;            // of the image
  int grid_width = 0, grid_height = 0;  // in cells
};

SampleGrid sampleGridOf(const OrganizedCloud& cloud, int stride) {
  return {stride, cloud.width, cloud.height, (cloud.width + stride - 1) / stride,
          (cloud.height + stride - 1) / stride};
}

// Step 1 with a stride > 1: every table point counts (`full_pixels`), the
// sampled ones also go to `points` and `pixels` and are entered in
// `sample_at`. (Not collectTablePoints followed by a pick of the sampled
// points: copying every point first made the stride-2 table stage 1.13 of
// this in tables_bench.)
void collectSampledTablePoints(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                               const TableConfig& config, const SampleGrid& grid,
                               DetectionScratch& scratch, TableDetection& result) {
  const int stride = grid.stride, width = grid.width, height = grid.height;
  const int grid_width = grid.grid_width;
  std::vector<Eigen::Vector3f>& points = scratch.points;
  std::vector<int>& pixels = scratch.pixels;
  std::vector<int>& full_pixels_buffer = scratch.full_pixels;
  std::vector<int>& sample_at = scratch.sample_at;
  sample_at.assign(static_cast<std::size_t>(grid_width) * grid.grid_height, -1);
  for (int y = 0; y < height; ++y) {
    const bool sampled_row = y % stride == 0;
    const std::size_t row = static_cast<std::size_t>(y) * width;
    const std::uint8_t* label_row = labels.labels.data() + row;
    for (int x = 0; x < width; ++x) {
      if (label_row[x] != kTableLabel) {
        // Skip to the next table pixel (as collectTablePoints).
        const void* next =
            std::memchr(label_row + x, kTableLabel, static_cast<std::size_t>(width - x));
        if (!next) break;
        x = static_cast<int>(static_cast<const std::uint8_t*>(next) - label_row);
      }
      const std::size_t i = row + static_cast<std::size_t>(x);
      const Eigen::Vector3f& p = cloud_ground.points[i];
      const TablePoint kind = classifyTablePoint(p, config);
      if (kind == TablePoint::kNonFinite) {
        ++result.nonfinite_points;
        continue;
      }
      if (kind == TablePoint::kImplausible) {
        ++result.implausible_points;
        continue;
      }
      ++result.table_points;
      full_pixels_buffer.push_back(static_cast<int>(i));
      if (!sampled_row || x % stride != 0) continue;
      sample_at[static_cast<std::size_t>(y / stride) * grid_width + x / stride] =
          static_cast<int>(points.size());
      points.push_back(p);
      pixels.push_back(static_cast<int>(i));
    }
  }
}

// Step 1's diagnostics; false (with the reason) when no point is left to
// cluster.
bool reportTablePoints(const TableConfig& config, std::size_t sampled_points,
                       TableDetection& result) {
  if (result.nonfinite_points > 0) {
    result.diagnostics.push_back(std::to_string(result.nonfinite_points) +
                                 " table-labelled points with non-finite coordinates ignored");
  }
  if (result.implausible_points > 0) {
    result.diagnostics.push_back(
        std::to_string(result.implausible_points) + " table-labelled points outside [" +
        fmt(config.min_table_height_m) + ", " + fmt(config.max_table_height_m) +
        "] m height (tables.min/max_table_height_m) or beyond 100 m ignored");
  }
  if (result.table_points == 0) {
    result.diagnostics.push_back("no table-labelled points at table height: no tables");
    return false;
  }
  if (sampled_points == 0) {
    result.unsampled_points = result.table_points;
    result.diagnostics.push_back(
        std::to_string(result.table_points) + " table points, none at a sampled pixel " +
        "(tables.point_stride " + std::to_string(config.point_stride) + "): no tables");
    return false;
  }
  return true;
}

// Step 2 with a stride > 1: each table point joins the cluster of a sampled
// corner of its grid cell within the tolerance (scratch.full_cluster, -1 = none;
// tables.hpp), its own corner first; the others are counted as unsampled.
void joinSampledClusters(const OrganizedCloud& cloud_ground, const TableConfig& config,
                         const SampleGrid& grid, DetectionScratch& scratch,
                         TableDetection& result) {
  const int stride = grid.stride, width = grid.width;
  const int grid_width = grid.grid_width, grid_height = grid.grid_height;
  const std::vector<int>& full_pixels = scratch.full_pixels;
  const std::vector<Eigen::Vector3f>& points = scratch.points;
  const std::vector<int>& sample_at = scratch.sample_at;
  const std::vector<int>& cluster_of = scratch.cluster_of;
  std::vector<int>& full_cluster_buffer = scratch.full_cluster;
  const float tol2 = config.cluster_tolerance_m * config.cluster_tolerance_m;
  full_cluster_buffer.resize(full_pixels.size());
  for (std::size_t k = 0; k < full_pixels.size(); ++k) {
    const int pixel = full_pixels[k];
    const int gx = (pixel % width) / stride, gy = (pixel / width) / stride;
    const Eigen::Vector3f& p = cloud_ground.points[static_cast<std::size_t>(pixel)];
    int cluster = -1;
    // Own corner first (the point itself when it is sampled), then the
    // cell's other corners.
    for (int corner = 0; corner < 4 && cluster < 0; ++corner) {
      const int cx = gx + (corner & 1), cy = gy + (corner >> 1);
      if (cx >= grid_width || cy >= grid_height) continue;
      const int sample = sample_at[static_cast<std::size_t>(cy) * grid_width + cx];
      if (sample >= 0 && (points[sample] - p).squaredNorm() <= tol2) cluster = cluster_of[sample];
    }
    full_cluster_buffer[k] = cluster;
    if (cluster < 0) ++result.unsampled_points;
  }
  if (result.unsampled_points > 0) {
    result.diagnostics.push_back(std::to_string(result.unsampled_points) +
                                 " table points with no sampled point " +
                                 "within tables.cluster_tolerance_m (tables.point_stride " +
                                 std::to_string(stride) + ") left out");
  }
}

// Counting sort of `of` (cluster per point, -1 = none) into `start` and
// `order`, a run of one cluster at a time: points come in pixel order, so
// a table's points lie in long runs of one cluster, and point by point
// every count and every placement waited for the previous one's store to
// the same counter. Members stay in ascending point order, hence ascending
// pixel order, so table.pixels needs no sort, and sums over members run in
// the same order as before.
void groupByCluster(int clusters, const std::vector<int>& of, std::vector<int>& start,
                    std::vector<int>& order, std::vector<int>& fill) {
  start.assign(static_cast<std::size_t>(clusters) + 1, 0);
  const std::size_t count = of.size();
  for (std::size_t i = 0, end = 0; i < count; i = end) {
    end = detail::intRunEnd(of.data(), i, count);
    if (of[i] >= 0) start[of[i] + 1] += static_cast<int>(end - i);
  }
  for (int c = 0; c < clusters; ++c) start[c + 1] += start[c];
  order.resize(static_cast<std::size_t>(start[clusters]));
  fill.assign(start.begin(), start.end() - 1);
  for (std::size_t i = 0, end = 0; i < count; i = end) {
    end = detail::intRunEnd(of.data(), i, count);
    const int c = of[i];
    if (c < 0) continue;
    std::iota(order.begin() + fill[c], order.begin() + fill[c] + static_cast<int>(end - i),
              static_cast<int>(i));
    fill[c] += static_cast<int>(end - i);
  }
}

// The members of each cluster: those of cluster c are members[start[c] ..
// start[c + 1]) (indices into the full table points), and sample_members
// [sample_start[c] .. sample_start[c + 1]) (indices into the sampled points).
// With a stride of 1 the two are the same lists.
struct ClusterMembers {
  const std::vector<int>& start;
  const std::vector<int>& members;
  const std::vector<int>& sample_start;
  const std::vector<int>& sample_members;
};


// Step 3's checks of one described cluster of n points, in this order; a
// rejected one is counted and its reason goes to the diagnostics. With
// normals, also sets the table's horizontal share.
bool acceptTable(const ClusterOutcome& outcome, const MemberSums& sums, int n, bool with_normals,
                 bool soft_top, const TableConfig& config, TableCluster& table,
                 TableDetection& result) {
  if (!outcome.ok) {
    ++result.clusters_rejected;
    result.diagnostics.push_back(outcome.reason + ": dropped");
    return false;
  }
  if (table.top_area_m2 < config.min_top_area_m2) {
    ++result.clusters_rejected;
    result.diagnostics.push_back("cluster of " + std::to_string(n) + " points with a top of " +
                                 fmt(table.top_area_m2) + " m² (below tables.min_top_area_m2 " +
                                 fmt(config.min_top_area_m2) + "): dropped");
    return false;
  }
  if (soft_top) {
    ++result.clusters_rejected;
    ++result.soft_tops;
    result.diagnostics.push_back(
        "cluster of " + std::to_string(n) + " points with a top of " + fmt(table.top_area_m2) +
        " m² whose horizontal points are " + fmt(100.0 * table.flat_share) +
        " % flat (below tables.min_flat_share " + fmt(config.min_flat_share) +
        "): a soft top (bed, sofa), not a table: dropped");
    return false;
  }
  if (table.mean_confidence < config.min_confidence) {
    ++result.clusters_rejected;
    result.diagnostics.push_back("cluster of " + std::to_string(n) +
                                 " points with mean confidence " + fmt(table.mean_confidence) +
                                 " (below tables.min_confidence " + fmt(config.min_confidence) +
                                 "): dropped");
    return false;
  }
  if (with_normals) {
    table.horizontal_share =
        sums.valid_normals > 0 ? static_cast<float>(sums.horizontal) / sums.valid_normals : 0.0f;
    if (table.horizontal_share < config.min_horizontal_share) {
      ++result.clusters_rejected;
      result.diagnostics.push_back("cluster of " + std::to_string(n) + " points with " +
                                   fmt(100.0 * table.horizontal_share) +
                                   " % horizontal points (below " + "tables.min_horizontal_share " +
                                   fmt(config.min_horizontal_share) + "): dropped");
      return false;
    }
  }
  return true;
}

// Step 3: each cluster of a size within the limits described (geometry from
// its sampled points, confidence and horizontal share from all of them) and,
// when it passes the checks, appended to result.tables with its pixels.
void describeClusters(int clusters, const ClusterMembers& m, const std::vector<int>& full_pixels,
                      const OrganizedCloud& cloud_ground, const LabelImage& labels,
                      const NormalImage* normals_ground, const TableConfig& config,
                      DetectionScratch& scratch, TableDetection& result) {
  const float cos_tilt = std::cos(config.horizontal_tilt_deg * static_cast<float>(M_PI) / 180.0f);
  int small_clusters = 0, largest_small = 0;
  std::vector<TableCluster>& tables = result.tables;  // empty (resetDetection)
  std::vector<Eigen::Vector3f>& cluster_points = scratch.cluster_points;
  // The table being described: a spare's buffers, kept across rejected
  // clusters and replaced when it is taken.
  TableCluster table = takeSpareTable(scratch.spare);
  for (int c = 0; c < clusters; ++c) {
    const int* member = m.members.data() + m.start[c];
    const int n = m.start[c + 1] - m.start[c];
    if (n < config.min_cluster_points) {
      ++small_clusters;
      largest_small = std::max(largest_small, n);
      continue;
    }
    if (n > config.max_cluster_points) {
      ++result.clusters_rejected;
      result.diagnostics.push_back("cluster of " + std::to_string(n) +
                                   " points above tables.max_cluster_points (" +
                                   std::to_string(config.max_cluster_points) + ") dropped");
      continue;
    }
    const int* sample_member = m.sample_members.data() + m.sample_start[c];
    const int samples = m.sample_start[c + 1] - m.sample_start[c];
    cluster_points.resize(static_cast<std::size_t>(samples));
    gatherByIndex(scratch.points.data(), sample_member, samples, cluster_points.data());
    const MemberSums sums =
        memberSums(member, n, full_pixels.data(), labels.confidence, normals_ground, cos_tilt);
    table = reusedTable(std::move(table));
    table.mean_confidence = static_cast<float>(sums.confidence / n);
    const ClusterOutcome outcome = describeCluster(cluster_points, n, config, table);
    const bool soft =
        outcome.ok && table.top_area_m2 >= config.min_top_area_m2 &&
        softTop(member, n, full_pixels.data(), cloud_ground, normals_ground, config, table);
    if (!acceptTable(outcome, sums, n, normals_ground != nullptr, soft, config, table, result)) {
      if (soft) {
        const std::size_t at = result.soft_top_pixels.size();
        result.soft_top_pixels.resize(at + static_cast<std::size_t>(n));
        gatherByIndex(full_pixels.data(), member, n, result.soft_top_pixels.data() + at);
      }
      continue;
    }
    // A spare list that is too small grows with a quarter to spare, so that
    // over a stream the lists settle at sizes that fit the tables seen.
    const auto pixel_count = static_cast<std::size_t>(n);
    if (table.pixels.capacity() < pixel_count) table.pixels.reserve(pixel_count + pixel_count / 4);
    table.pixels.resize(pixel_count);
    gatherByIndex(full_pixels.data(), member, n, table.pixels.data());
    tables.push_back(std::move(table));
    table = takeSpareTable(scratch.spare);
  }
  if (scratch.spare.size() < kMaxSpareTables) scratch.spare.push_back(std::move(table));
  if (small_clusters > 0) {
    result.clusters_rejected += small_clusters;
    result.diagnostics.push_back(
        std::to_string(small_clusters) + " clusters below tables.min_cluster_points (" +
        std::to_string(config.min_cluster_points) + ") dropped, the largest of " +
        std::to_string(largest_small) + " points");
  }
}

// Largest first, ties in cluster order: a stable insertion sort (a frame
// has a handful of tables; std::stable_sort allocates a buffer).
void sortLargestFirst(std::vector<TableCluster>& tables) {
  for (std::size_t k = 1; k < tables.size(); ++k) {
    for (std::size_t j = k; j > 0 && tables[j - 1].point_count < tables[j].point_count; --j) {
      std::swap(tables[j - 1], tables[j]);
    }
  }
}

// Steps 4 and 5: each table's id and search positions, then their
// reachability from one grid around all of them.
void placeSearchPositions(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                          const TableConfig& config, std::vector<TableCluster>& tables,
                          std::vector<Eigen::Vector2f>& position_xy) {
  Eigen::AlignedBox2f region;
  position_xy.clear();
  for (std::size_t k = 0; k < tables.size(); ++k) {
    tables[k].id = static_cast<int>(k);
    tables[k].search_positions = computeSearchPositions(tables[k], config);
    for (const auto& p : tables[k].search_positions) {
      region.extend(p.xy);
      position_xy.push_back(p.xy);
    }
  }
  if (tables.empty()) return;
  const float margin = config.robot_radius_m + config.floor_cell_m;
  region.extend(region.min() - Eigen::Vector2f::Constant(margin));
  region.extend(region.max() + Eigen::Vector2f::Constant(margin));
  const ReachabilityGrid grid(cloud_ground, labels, region, position_xy, config);
  for (auto& found : tables) {
    for (auto& position : found.search_positions) grid.assess(position);
  }
}

}  // namespace

void detectTablesInto(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                      const TableConfig& config, const NormalImage* normals_ground,
                      TableDetection& result) {
  thread_local DetectionScratch scratch_tls;
  DetectionScratch& scratch = scratch_tls;
  resetDetection(result, scratch.spare);
  validateTableConfig(config);
  checkNormals(cloud_ground, normals_ground);
  if (cloud_ground.points.empty()) {
    result.diagnostics.push_back(
        "no ground-aligned cloud (no ground plane for this frame): no tables");
    return;
  }
  checkInputs(cloud_ground, labels);

  // 1. Table points: every one (`full_pixels`, for pixels, counts,
  // confidence and normals) and those at the sampled pixels (`points`,
  // `pixels`, for clustering and geometry; see "Point stride" in
  // tables.hpp). With a stride of 1 the two are the same lists.
  const SampleGrid grid = sampleGridOf(cloud_ground, config.point_stride);
  const bool strided = grid.stride > 1;
  scratch.points.clear();
  scratch.pixels.clear();
  scratch.full_pixels.clear();
  if (strided) {
    collectSampledTablePoints(cloud_ground, labels, config, grid, scratch, result);
  } else {
    collectTablePoints(cloud_ground, labels, config, scratch.points, scratch.pixels, result);
  }
  if (!reportTablePoints(config, scratch.points.size(), result)) return;

  // 2. Clusters of the sampled points (and, with a stride, of the others),
  // then the members of each cluster, full and sampled.
  clusterPointsInto(scratch.points, config.cluster_tolerance_m,
                    PointGrid{&scratch.pixels, grid.width, grid.stride}, scratch.cluster_of);
  const int clusters = *std::max_element(scratch.cluster_of.begin(), scratch.cluster_of.end()) + 1;
  if (strided) joinSampledClusters(cloud_ground, config, grid, scratch, result);
  const std::vector<int>& full_pixels = strided ? scratch.full_pixels : scratch.pixels;
  const std::vector<int>& full_cluster = strided ? scratch.full_cluster : scratch.cluster_of;
  groupByCluster(clusters, full_cluster, scratch.member_start, scratch.members, scratch.fill);
  if (strided) {
    groupByCluster(clusters, scratch.cluster_of, scratch.sample_start, scratch.sample_members,
                   scratch.fill);
  }
  const ClusterMembers members{scratch.member_start, scratch.members,
                               strided ? scratch.sample_start : scratch.member_start,
                               strided ? scratch.sample_members : scratch.members};

  // 3. Geometry and checks, one cluster at a time.
  describeClusters(clusters, members, full_pixels, cloud_ground, labels, normals_ground, config,
                   scratch, result);
  sortLargestFirst(result.tables);

  // 4. Search positions, 5. their reachability.
  placeSearchPositions(cloud_ground, labels, config, result.tables, scratch.position_xy);
}

std::vector<TableCluster> findTables(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                                     const TableConfig& config) {
  return detectTables(cloud_ground, labels, config).tables;
}

}  // namespace findmug
