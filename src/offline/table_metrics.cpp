// Table detection measured as objects (see table_metrics.hpp).
#include "findmug/offline/table_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/map/table_map.hpp"

namespace findmug {

namespace {

double median(std::vector<float> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = values.begin() + static_cast<long>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  if (values.size() % 2 == 1) return *mid;
  const float below = *std::max_element(values.begin(), mid);
  return 0.5 * (static_cast<double>(below) + *mid);
}

double ratio(int a, int b) {
  return b > 0 ? static_cast<double>(a) / b : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

void validateTableMetricsConfig(const TableMetricsConfig& config) {
  if (config.min_instance_points < 1) {
    throw Error("table_metrics.min_instance_points = " +
                std::to_string(config.min_instance_points) + ": must be >= 1");
  }
  if (!(config.min_iou > 0.0f && config.min_iou <= 1.0f)) {
    throw Error("table_metrics.min_iou = " + std::to_string(config.min_iou) +
                ": must be in (0, 1]");
  }
  if (!(config.searchable_min_top_area_m2 >= 0.0f)) {
    throw Error("table_metrics.searchable_min_top_area_m2 = " +
                std::to_string(config.searchable_min_top_area_m2) + ": must be >= 0");
  }
  if (!(config.searchable_min_overlap > 0.0f && config.searchable_min_overlap <= 1.0f)) {
    throw Error("table_metrics.searchable_min_overlap = " +
                std::to_string(config.searchable_min_overlap) + ": must be in (0, 1]");
  }
  if (!(config.searchable_max_height_error_m >= 0.0f)) {
    throw Error("table_metrics.searchable_max_height_error_m = " +
                std::to_string(config.searchable_max_height_error_m) + ": must be >= 0");
  }
}

std::vector<TableCluster> groundTruthTables(const OrganizedCloud& cloud_ground,
                                            const std::vector<std::uint8_t>& gt_labels,
                                            const TableConfig& tables,
                                            const TableMetricsConfig& config) {
  validateTableMetricsConfig(config);
  if (cloud_ground.points.empty()) return {};
  TableConfig truth_config = tables;
  truth_config.min_cluster_points = config.min_instance_points;
  // Instances are the exact partition of every table point, not a sample's.
  truth_config.point_stride = 1;
  // The detector's filters are not part of the instance definition.
  truth_config.min_top_area_m2 = 0.0f;
  truth_config.min_confidence = 0.0f;
  truth_config.min_horizontal_share = 0.0f;
  truth_config.max_cluster_points =
      std::max(truth_config.max_cluster_points, static_cast<int>(cloud_ground.points.size()));
  LabelImage labels;
  labels.width = cloud_ground.width;
  labels.height = cloud_ground.height;
  labels.labels = gt_labels;
  return detectTables(cloud_ground, labels, truth_config).tables;
}

double maskIoU(const std::vector<int>& a, const std::vector<int>& b) {
  if (a.empty() && b.empty()) return 0.0;
  std::size_t i = 0, j = 0, common = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i] < b[j]) {
      ++i;
    } else if (b[j] < a[i]) {
      ++j;
    } else {
      ++common, ++i, ++j;
    }
  }
  return static_cast<double>(common) / static_cast<double>(a.size() + b.size() - common);
}

std::vector<TableMatch> matchTables(const std::vector<TableCluster>& truth,
                                    const std::vector<TableCluster>& detected, float min_iou) {
  std::vector<TableMatch> candidates;
  for (std::size_t t = 0; t < truth.size(); ++t) {
    for (std::size_t d = 0; d < detected.size(); ++d) {
      const double iou = maskIoU(truth[t].pixels, detected[d].pixels);
      if (iou >= min_iou && iou > 0.0) {
        TableMatch m;
        m.truth = static_cast<int>(t);
        m.detected = static_cast<int>(d);
        m.iou = iou;
        candidates.push_back(m);
      }
    }
  }
  // Greedy by IoU; ties by index so that the result does not depend on sort order.
  std::sort(candidates.begin(), candidates.end(), [](const TableMatch& a, const TableMatch& b) {
    if (a.iou != b.iou) return a.iou > b.iou;
    if (a.truth != b.truth) return a.truth < b.truth;
    return a.detected < b.detected;
  });
  std::vector<bool> truth_used(truth.size(), false), detected_used(detected.size(), false);
  std::vector<TableMatch> matches;
  for (TableMatch m : candidates) {
    if (truth_used[static_cast<std::size_t>(m.truth)] ||
        detected_used[static_cast<std::size_t>(m.detected)]) {
      continue;
    }
    truth_used[static_cast<std::size_t>(m.truth)] = true;
    detected_used[static_cast<std::size_t>(m.detected)] = true;
    const TableCluster& a = truth[static_cast<std::size_t>(m.truth)];
    const TableCluster& b = detected[static_cast<std::size_t>(m.detected)];
    m.height_error_m = std::abs(a.top_height - b.top_height);
    m.centroid_error_m = (a.centroid.head<2>() - b.centroid.head<2>()).norm();
    const float cosine =
        std::min(1.0f, std::abs(a.major_axis.normalized().dot(b.major_axis.normalized())));
    m.axis_error_deg = std::acos(cosine) * 180.0f / static_cast<float>(M_PI);
    matches.push_back(m);
  }
  return matches;
}

void TableMetrics::add(int truth_tables, int detected_tables,
                       const std::vector<TableMatch>& matches) {
  truth_ += truth_tables;
  detected_ += detected_tables;
  for (const auto& m : matches) {
    height_errors_.push_back(m.height_error_m);
    centroid_errors_.push_back(m.centroid_error_m);
    axis_errors_.push_back(m.axis_error_deg);
  }
}

double TableMetrics::precision() const { return ratio(matched(), detected_); }
double TableMetrics::recall() const { return ratio(matched(), truth_); }
double TableMetrics::medianHeightError() const { return median(height_errors_); }
double TableMetrics::medianCentroidError() const { return median(centroid_errors_); }
double TableMetrics::medianAxisErrorDeg() const { return median(axis_errors_); }

namespace {

// Signed area of a polygon's vertex order: > 0 counter-clockwise.
double orientation(const std::vector<Eigen::Vector2d>& polygon) {
  double twice = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& p = polygon[i];
    const Eigen::Vector2d& q = polygon[(i + 1) % polygon.size()];
    twice += p.x() * q.y() - q.x() * p.y();
  }
  return twice;
}

std::vector<Eigen::Vector2d> counterClockwise(const std::vector<Eigen::Vector2f>& polygon) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : polygon) out.push_back(p.cast<double>());
  if (orientation(out) < 0.0) std::reverse(out.begin(), out.end());
  return out;
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
}

}  // namespace

double convexOverlapArea(const std::vector<Eigen::Vector2f>& a,
                         const std::vector<Eigen::Vector2f>& b) {
  if (a.size() < 3 || b.size() < 3) return 0.0;
  // Sutherland-Hodgman: clip `a` by each edge of the convex `b` (both CCW).
  std::vector<Eigen::Vector2d> subject = counterClockwise(a);
  const std::vector<Eigen::Vector2d> clip = counterClockwise(b);
  for (std::size_t e = 0; e < clip.size() && !subject.empty(); ++e) {
    const Eigen::Vector2d& c0 = clip[e];
    const Eigen::Vector2d& c1 = clip[(e + 1) % clip.size()];
    std::vector<Eigen::Vector2d> kept;
    for (std::size_t i = 0; i < subject.size(); ++i) {
      const Eigen::Vector2d& p = subject[i];
      const Eigen::Vector2d& q = subject[(i + 1) % subject.size()];
      const double sp = cross(c0, c1, p), sq = cross(c0, c1, q);
      if (sp >= 0.0) kept.push_back(p);
      if ((sp >= 0.0) != (sq >= 0.0)) kept.push_back(p + (q - p) * (sp / (sp - sq)));
    }
    subject = std::move(kept);
  }
  if (subject.size() < 3) return 0.0;
  return 0.5 * std::abs(orientation(subject));
}

double topOverlap(const TableCluster& a, const TableCluster& b) {
  const double smaller =
      std::min<double>(std::abs(polygonArea(a.hull)), std::abs(polygonArea(b.hull)));
  if (!(smaller > 0.0)) return 0.0;
  return convexOverlapArea(a.hull, b.hull) / smaller;
}

SearchableFrame measureSearchableTables(const std::vector<TableCluster>& truth,
                                        const std::vector<TableCluster>& detected,
                                        const TableMetricsConfig& config) {
  validateTableMetricsConfig(config);
  struct Pair {
    double overlap;
    std::size_t t, d;
  };
  std::vector<Pair> pairs;
  for (std::size_t t = 0; t < truth.size(); ++t) {
    for (std::size_t d = 0; d < detected.size(); ++d) {
      if (std::abs(truth[t].top_height - detected[d].top_height) >
          config.searchable_max_height_error_m) {
        continue;
      }
      const double overlap = topOverlap(truth[t], detected[d]);
      if (overlap >= config.searchable_min_overlap && overlap > 0.0) pairs.push_back({overlap, t, d});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    if (a.overlap != b.overlap) return a.overlap > b.overlap;
    if (a.t != b.t) return a.t < b.t;
    return a.d < b.d;
  });
  std::vector<int> match_of_detected(detected.size(), -1);
  std::vector<bool> truth_used(truth.size(), false);
  for (const Pair& p : pairs) {
    if (truth_used[p.t] || match_of_detected[p.d] >= 0) continue;
    truth_used[p.t] = true;
    match_of_detected[p.d] = static_cast<int>(p.t);
  }
  auto searchable = [&](std::size_t t) {
    return truth[t].top_area_m2 >= config.searchable_min_top_area_m2;
  };
  SearchableFrame out;
  out.detected = static_cast<int>(detected.size());
  for (std::size_t t = 0; t < truth.size(); ++t) out.searchable += searchable(t) ? 1 : 0;
  for (std::size_t d = 0; d < detected.size(); ++d) {
    const int t = match_of_detected[d];
    if (t < 0) {
      ++out.false_tables;
    } else if (searchable(static_cast<std::size_t>(t))) {
      ++out.searchable_matched;
    } else {
      ++out.detected_small;
    }
  }
  return out;
}

void SearchableMetrics::add(const SearchableFrame& f) {
  ++frames_;
  searchable_ += f.searchable;
  matched_ += f.searchable_matched;
  detected_ += f.detected;
  detected_small_ += f.detected_small;
  false_tables_ += f.false_tables;
  frames_with_false_ += f.false_tables > 0 ? 1 : 0;
}

double SearchableMetrics::precision() const { return ratio(matched_, detected_ - detected_small_); }
double SearchableMetrics::recall() const { return ratio(matched_, searchable_); }
double SearchableMetrics::falseTableFrameShare() const { return ratio(frames_with_false_, frames_); }

std::vector<PrecisionRecallPoint> precisionRecallCurve(std::vector<ScoredDetection> detections,
                                                       int truth) {
  if (truth < 0) throw Error("precisionRecallCurve: " + std::to_string(truth) + " true instances");
  for (const auto& d : detections) {
    if (!std::isfinite(d.score)) {
      throw Error("precisionRecallCurve: non-finite detection score " + std::to_string(d.score));
    }
  }
  std::sort(detections.begin(), detections.end(),
            [](const ScoredDetection& a, const ScoredDetection& b) { return a.score > b.score; });
  std::vector<PrecisionRecallPoint> curve;
  int detected = 0, matched = 0;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    ++detected;
    matched += detections[i].matched ? 1 : 0;
    // A threshold keeps every detection of equal score: one point per score.
    if (i + 1 < detections.size() && detections[i + 1].score == detections[i].score) continue;
    PrecisionRecallPoint p;
    p.threshold = detections[i].score;
    p.detected = detected;
    p.matched = matched;
    p.precision = ratio(matched, detected);
    p.recall = ratio(matched, truth);
    curve.push_back(p);
  }
  return curve;
}

const PrecisionRecallPoint* operatingPoint(const std::vector<PrecisionRecallPoint>& curve,
                                           double min_precision) {
  const PrecisionRecallPoint* best = nullptr;
  for (const auto& p : curve) {
    if (!(p.precision >= min_precision) || p.matched == 0) continue;
    if (!best || p.recall > best->recall ||
        (p.recall == best->recall && p.precision > best->precision)) {
      best = &p;
    }
  }
  return best;
}

std::vector<SearchPosition> searchPositionsOfBox(const Eigen::Vector2f& center, float yaw,
                                                 const Eigen::Vector2f& size, float height,
                                                 const TableConfig& config) {
  TableCluster box;
  box.center = center;
  box.major_axis = Eigen::Vector2f(std::cos(yaw), std::sin(yaw));
  box.minor_axis = Eigen::Vector2f(-std::sin(yaw), std::cos(yaw));
  box.extents = 0.5f * size;
  box.top_height = height;
  box.centroid = Eigen::Vector3f(center.x(), center.y(), height);
  return computeSearchPositions(box, config);
}

std::vector<PositionError> nearestPositionErrors(const std::vector<SearchPosition>& predicted,
                                                 const std::vector<SearchPosition>& truth) {
  std::vector<PositionError> out(predicted.size());
  for (std::size_t k = 0; k < predicted.size(); ++k) {
    float best = std::numeric_limits<float>::infinity();
    for (std::size_t t = 0; t < truth.size(); ++t) {
      const float d = (predicted[k].xy - truth[t].xy).norm();
      if (d < best) {
        best = d;
        out[k].nearest = static_cast<int>(t);
      }
    }
    if (out[k].nearest < 0) continue;
    out[k].distance_m = best;
    const float diff =
        std::remainder(predicted[k].yaw - truth[static_cast<std::size_t>(out[k].nearest)].yaw,
                       2.0f * static_cast<float>(M_PI));
    out[k].yaw_error_deg = std::abs(diff) * 180.0f / static_cast<float>(M_PI);
  }
  return out;
}

void SearchPositionMetrics::add(const std::vector<PositionError>& errors,
                                const std::vector<bool>& flagged_reachable,
                                const std::vector<bool>& reachable_in_truth) {
  if (flagged_reachable.size() != errors.size() || reachable_in_truth.size() != errors.size()) {
    throw Error("SearchPositionMetrics::add: " + std::to_string(errors.size()) + " errors, " +
                std::to_string(flagged_reachable.size()) + " reachability flags and " +
                std::to_string(reachable_in_truth.size()) + " true reachabilities");
  }
  predicted_ += static_cast<int>(errors.size());
  for (std::size_t k = 0; k < errors.size(); ++k) {
    reachable_ += reachable_in_truth[k] ? 1 : 0;
    flagged_ += flagged_reachable[k] ? 1 : 0;
    flagged_truly_ += flagged_reachable[k] && reachable_in_truth[k] ? 1 : 0;
  }
  for (const auto& e : errors) {
    if (e.nearest < 0) continue;
    distances_.push_back(e.distance_m);
    yaw_errors_.push_back(e.yaw_error_deg);
  }
}

double SearchPositionMetrics::reachableShare() const { return ratio(reachable_, predicted_); }
double SearchPositionMetrics::flaggedReachableShare() const {
  return ratio(flagged_truly_, flagged_);
}
double SearchPositionMetrics::medianPositionError() const { return median(distances_); }
double SearchPositionMetrics::medianYawErrorDeg() const { return median(yaw_errors_); }

}  // namespace findmug
