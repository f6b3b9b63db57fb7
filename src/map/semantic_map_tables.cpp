// semantic_map_tables.cpp — tables from the fused votes, their support, and the fused labels
// projected into a frame (see semantic_map.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/map/table_map.hpp"
#include "semantic_map_internal.hpp"

namespace findmug {

using namespace semantic_map_detail;

// ---- tables ---------------------------------------------------------------------------------

std::vector<FusedTable> SemanticMap::tables(std::vector<std::string>* diagnostics) {
  // Every voxel with enough evidence as one point of an unorganized cloud (width n,
  // height 1), labelled with its most voted label.
  // The table stage works near its origin (it refuses points 100 m away, and floats lose
  // millimetres far out): the voxels go in relative to their mean position on the floor,
  // those more than kTableRadiusM from it are left out, and the tables are moved back.
  constexpr double kTableRadiusM = 90.0;
  OrganizedCloud cloud;
  LabelImage labels;
  std::vector<Eigen::Vector3d> centres;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& [key, v] : voxels_) {
    if (!occupied(v) || v.frames < map_config_.min_voxel_frames) continue;
    float confidence = 0.0f;
    std::uint8_t label = labelOf(v, &confidence);
    if (label == kVoidLabel) continue;
    // As per frame (tables.table_weight, weightTableProbability): the table votes count
    // table_weight times when the voxel's label is decided for the table stage.
    const int table = static_cast<int>(Label::Table);
    if (label != table && v.votes[table] * table_config_.table_weight > v.votes[label]) {
      std::uint32_t total = 0;
      for (std::uint16_t n : v.votes) total += n;
      label = static_cast<std::uint8_t>(table);
      confidence = static_cast<float>(v.votes[table]) / static_cast<float>(total);
    }
    centres.push_back(centreOf(key));
    mean += centres.back().head<2>();
    labels.labels.push_back(label);
    labels.confidence.push_back(confidence);
  }
  if (!centres.empty()) mean /= static_cast<double>(centres.size());
  // Whole voxels: the shift moves no centre off the grid.
  const double voxel_m = map_config_.voxel_size_m;
  const Eigen::Vector2d shift = (mean / voxel_m).array().round().matrix() * voxel_m;
  {
    LabelImage near;
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const Eigen::Vector2d xy = centres[i].head<2>() - shift;
      if (xy.norm() > kTableRadiusM) continue;
      cloud.points.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                                static_cast<float>(centres[i].z()));
      near.labels.push_back(labels.labels[i]);
      near.confidence.push_back(labels.confidence[i]);
    }
    labels = std::move(near);
  }
  // Deterministic order whatever the hash table's (ties in the clustering and geometry).
  {
    std::vector<std::size_t> order(cloud.points.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      const auto& p = cloud.points[a];
      const auto& q = cloud.points[b];
      return std::tie(p.x(), p.y(), p.z()) < std::tie(q.x(), q.y(), q.z());
    });
    OrganizedCloud sorted;
    LabelImage sorted_labels;
    for (std::size_t i : order) {
      sorted.points.push_back(cloud.points[i]);
      sorted_labels.labels.push_back(labels.labels[i]);
      sorted_labels.confidence.push_back(labels.confidence[i]);
    }
    cloud = std::move(sorted);
    labels = std::move(sorted_labels);
  }
  const int n = static_cast<int>(cloud.points.size());
  cloud.width = labels.width = n;
  cloud.height = labels.height = n > 0 ? 1 : 0;
  if (n == 0) cloud.width = labels.width = 0;
  cloud.colors.assign(cloud.points.size(), Rgb8{});

  TableConfig config = table_config_;
  config.point_stride = 1;
  config.min_cluster_points = map_config_.min_table_voxels;
  config.max_cluster_points = std::max(config.min_cluster_points, n);
  // Neighbouring voxel centres are one voxel apart, diagonal ones up to sqrt(3) voxels.
  config.cluster_tolerance_m =
      std::max(config.cluster_tolerance_m, 1.75f * map_config_.voxel_size_m);
  std::vector<FusedTable> out;
  if (n == 0) {
    previous_tables_.clear();
    return out;
  }
  TableDetection detection = detectTables(cloud, labels, config, nullptr);
  if (diagnostics) *diagnostics = std::move(detection.diagnostics);

  std::vector<bool> used(previous_tables_.size(), false);
  std::vector<MappedId> now;
  for (TableCluster& detected : detection.tables) {
    FusedTable fused;
    fused.voxels = detected.point_count;
    detected.pixels.clear();
    TableCluster table = transformTable(detected, Pose2D{shift.x(), shift.y(), 0.0});
    // The earlier table it overlaps most, or failing that the nearest within the gap.
    int best = -1;
    float best_overlap = 0.0f, best_gap = map_config_.table_match_gap_m;
    for (std::size_t j = 0; j < previous_tables_.size(); ++j) {
      if (used[j]) continue;
      const auto& hull = previous_tables_[j].hull;
      const float overlap = polygonArea(intersectConvex(table.hull, hull));
      if (overlap > best_overlap) {
        best_overlap = overlap;
        best = static_cast<int>(j);
      } else if (best_overlap == 0.0f) {
        const float gap = convexGap(table.hull, hull);
        if (gap <= best_gap) {
          best_gap = gap;
          best = static_cast<int>(j);
        }
      }
    }
    if (best >= 0) {
      used[static_cast<std::size_t>(best)] = true;
      table.id = previous_tables_[static_cast<std::size_t>(best)].id;
    } else {
      table.id = next_table_id_++;
    }
    fused.table = std::move(table);
    countSupport(fused);
    now.push_back({fused.table.id, fused.table.hull});
    out.push_back(std::move(fused));
  }
  previous_tables_ = std::move(now);
  std::sort(out.begin(), out.end(),
            [](const FusedTable& a, const FusedTable& b) { return a.table.id < b.table.id; });
  return out;
}

void SemanticMap::countSupport(FusedTable& fused) const {
  const auto& hull = fused.table.hull;
  if (hull.size() < 3) return;
  const float voxel = map_config_.voxel_size_m;
  // The floor cells under the table's footprint (grown by one voxel), ascending.
  Eigen::Vector2f lo = hull.front(), hi = hull.front();
  for (const auto& p : hull) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::vector<std::uint64_t> cells;
  const auto x0 = static_cast<std::int64_t>(std::floor(lo.x() / voxel + 0.5f)) - 1;
  const auto x1 = static_cast<std::int64_t>(std::floor(hi.x() / voxel + 0.5f)) + 1;
  const auto y0 = static_cast<std::int64_t>(std::floor(lo.y() / voxel + 0.5f)) - 1;
  const auto y1 = static_cast<std::int64_t>(std::floor(hi.y() / voxel + 0.5f)) + 1;
  for (std::int64_t x = x0; x <= x1; ++x) {
    for (std::int64_t y = y0; y <= y1; ++y) {
      const Eigen::Vector2f centre(static_cast<float>(x) * voxel, static_cast<float>(y) * voxel);
      if (insideConvexOrNear(centre, hull, voxel)) cells.push_back(packIndices(x, y, 0));
    }
  }
  std::sort(cells.begin(), cells.end());
  std::set<std::uint64_t> viewpoints;
  for (const SupportRecord& record : support_) {
    std::uint32_t votes = 0;
    auto c = cells.begin();
    for (const auto& [column, count] : record.table_cells) {
      c = std::lower_bound(c, cells.end(), column);
      if (c == cells.end()) break;
      if (*c == column) votes += count;
    }
    if (votes >= static_cast<std::uint32_t>(map_config_.support_min_voxels)) {
      ++fused.frames;
      viewpoints.insert(record.viewpoint);
    }
  }
  fused.viewpoints = static_cast<int>(viewpoints.size());
}

// ---- fused labels into a frame ------------------------------------------------------------------

LabelImage SemanticMap::projectLabels(const OrganizedCloud& cloud, const LabelImage& labels,
                                      const Eigen::Isometry3d& camera_in_map, int* replaced) const {
  if (labels.width != cloud.width || labels.height != cloud.height ||
      labels.labels.size() != cloud.points.size() ||
      labels.confidence.size() != cloud.points.size()) {
    throw Error("semantic map: label image " + std::to_string(labels.width) + "x" +
                std::to_string(labels.height) + " does not match the cloud " +
                std::to_string(cloud.width) + "x" + std::to_string(cloud.height));
  }
  if (!camera_in_map.matrix().allFinite()) {
    throw Error("semantic map: camera pose is not finite");
  }
  LabelImage out = labels;
  int count = 0;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite()) continue;
    const Voxel* v = find(camera_in_map * p.cast<double>());
    if (!v || !occupied(*v)) continue;
    float confidence = 0.0f;
    const std::uint8_t label = labelOf(*v, &confidence);
    if (label == kVoidLabel) continue;
    out.labels[i] = label;
    out.confidence[i] = confidence;
    ++count;
  }
  if (replaced) *replaced = count;
  return out;
}

}  // namespace findmug
