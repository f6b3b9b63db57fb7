// table_top.cpp — the table-top test (tables.hpp, step 3b): a large cluster whose
// near-horizontal top points are not flat is a soft top (a bed, a sofa), not a table; and
// the relabelling of its pixels Unknown.
#include <cmath>
#include <limits>
#include <string>

#include "findmug/common/error.hpp"
#include "tables/tables_internal.hpp"

namespace findmug {

namespace tables_detail {

// The table-top test's measure (TableCluster::flat_share): over the members
// within `band` of the top height whose normal is within the horizontal tilt
// of vertical (|n.z| >= cos_horizontal), the share within the flat tilt
// (|n.z| >= cos_flat); NaN when none is horizontal. A non-finite normal
// fails both comparisons.
__attribute__((noinline)) float flatShare(const int* member, int n, const int* full_pixels,
                                          const OrganizedCloud& cloud, const NormalImage& normals,
                                          float top_height, float band, float cos_horizontal,
                                          float cos_flat) {
  int horizontal = 0, flat = 0;
  for (int k = 0; k < n; ++k) {
    const std::size_t pixel = static_cast<std::size_t>(full_pixels[member[k]]);
    const float nz = std::abs(normals.normals[pixel].z());
    const int in_band = std::abs(cloud.points[pixel].z() - top_height) <= band ? 1 : 0;
    horizontal += in_band & (nz >= cos_horizontal ? 1 : 0);
    flat += in_band & (nz >= cos_flat ? 1 : 0);
  }
  return horizontal > 0 ? static_cast<float>(flat) / static_cast<float>(horizontal)
                        : std::numeric_limits<float>::quiet_NaN();
}

// Step 3b, the table-top test: whether a described cluster's top is large
// and not flat (a bed or sofa: TableConfig::min_flat_share). Measures the
// table's flat_share when the top is large enough and there are normals.
bool softTop(const int* member, int n, const int* full_pixels, const OrganizedCloud& cloud,
             const NormalImage* normals, const TableConfig& config, TableCluster& table) {
  if (!normals || config.min_flat_share <= 0.0f ||
      table.top_area_m2 < config.soft_top_min_area_m2) {
    return false;
  }
  const float to_rad = static_cast<float>(M_PI) / 180.0f;
  table.flat_share = flatShare(member, n, full_pixels, cloud, *normals, table.top_height,
                               config.top_band_m, std::cos(config.horizontal_tilt_deg * to_rad),
                               std::cos(config.flat_tilt_deg * to_rad));
  // No horizontal top point (NaN): nothing says it is soft.
  return table.flat_share < config.min_flat_share;
}

}  // namespace tables_detail

int relabelSoftTops(const TableDetection& detection, LabelImage& labels) {
  const auto n = static_cast<long long>(labels.labels.size());
  // Checked first, so that a bad list leaves the image as it was.
  for (const int p : detection.soft_top_pixels) {
    if (p < 0 || p >= n) {
      throw Error("relabelSoftTops: pixel " + std::to_string(p) + " is outside the " +
                  std::to_string(labels.width) + "x" + std::to_string(labels.height) +
                  " label image");
    }
  }
  constexpr auto kUnknown = static_cast<std::uint8_t>(Label::Unknown);
  int changed = 0;
  for (const int p : detection.soft_top_pixels) {
    std::uint8_t& l = labels.labels[static_cast<std::size_t>(p)];
    if (l != static_cast<std::uint8_t>(Label::Table)) continue;
    l = kUnknown;
    ++changed;
  }
  return changed;
}

}  // namespace findmug
