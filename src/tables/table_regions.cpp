// The region vote of table_regions.hpp.
#include "findmug/tables/table_regions.hpp"

#include <cmath>
#include <string>

#include "findmug/common/error.hpp"
#include "common/scratch.hpp"

namespace findmug {

namespace {
// Columns of RegionFeatures::values (kRegionFeatureNames).
constexpr int kAreaColumn = 0;
constexpr int kCentroidHeightColumn = 3;
constexpr int kNormalAngleColumn = 5;
}  // namespace

RegionVoteResult voteTableRegions(const std::vector<std::uint8_t>& labels,
                                  const std::vector<float>& confidence,
                                  const std::vector<ClassProbabilities>& probabilities,
                                  const std::vector<float>& weights, const RegionFeatures& regions,
                                  const TableConfig& config) {
  const std::size_t n = labels.size();
  if (confidence.size() != n || probabilities.size() != n || weights.size() != n ||
      regions.segment_region.size() != n || regions.values.size() != n * kRegionFeatureDim) {
    throw Error("voteTableRegions: " + std::to_string(n) + " labels, " +
                std::to_string(confidence.size()) + " confidences, " +
                std::to_string(probabilities.size()) + " distributions, " +
                std::to_string(weights.size()) + " weights, " +
                std::to_string(regions.segment_region.size()) + " segment regions and " +
                std::to_string(regions.values.size()) + " region values (" +
                std::to_string(kRegionFeatureDim) + " per segment) must agree");
  }
  RegionVoteResult out{labels, confidence, 0, 0};
  const int count = regions.region_count;
  // Working memory kept per thread between frames (scratch.hpp).
  struct Buffers {
    std::vector<ClassProbabilities> sum;
    std::vector<double> weight;
    std::vector<char> eligible;
    std::vector<std::uint8_t> region_label;
    std::vector<float> region_confidence;
  };
  thread_local Buffers buffers;
  detail::Borrowed sum_buffer(buffers.sum);
  detail::Borrowed weight_buffer(buffers.weight);
  detail::Borrowed eligible_buffer(buffers.eligible);
  detail::Borrowed region_label_buffer(buffers.region_label);
  detail::Borrowed region_confidence_buffer(buffers.region_confidence);
  std::vector<ClassProbabilities>& sum = *sum_buffer;
  sum.assign(static_cast<std::size_t>(count), ClassProbabilities{});
  std::vector<double>& weight = *weight_buffer;
  weight.assign(static_cast<std::size_t>(count), 0.0);
  std::vector<char>& eligible = *eligible_buffer;
  eligible.assign(static_cast<std::size_t>(count), 0);
  const float max_tilt_rad = config.region_max_tilt_deg * static_cast<float>(M_PI) / 180.0f;
  for (std::size_t s = 0; s < n; ++s) {
    const int r = regions.segment_region[s];
    if (r < 0 || r >= count) {
      throw Error("voteTableRegions: segment " + std::to_string(s) + " has region " +
                  std::to_string(r) + " of " + std::to_string(count));
    }
    const float* v = regions.values.data() + s * kRegionFeatureDim;
    // Every patch of a region carries the region's values: test the first.
    eligible[static_cast<std::size_t>(r)] =
        v[kNormalAngleColumn] <= max_tilt_rad && v[kAreaColumn] >= config.region_min_area_m2 &&
        v[kCentroidHeightColumn] >= config.min_table_height_m &&
        v[kCentroidHeightColumn] <= config.max_table_height_m;
    for (int c = 0; c < kNumLabels; ++c) sum[static_cast<std::size_t>(r)][c] += weights[s] * probabilities[s][c];
    weight[static_cast<std::size_t>(r)] += weights[s];
  }
  std::vector<std::uint8_t>& region_label = *region_label_buffer;
  region_label.assign(static_cast<std::size_t>(count), kVoidLabel);
  std::vector<float>& region_confidence = *region_confidence_buffer;
  region_confidence.assign(static_cast<std::size_t>(count), 0.0f);
  for (int r = 0; r < count; ++r) {
    const auto k = static_cast<std::size_t>(r);
    if (!eligible[k] || weight[k] <= 0.0) continue;
    int best = 0;
    for (int c = 1; c < kNumLabels; ++c) {
      if (sum[k][c] > sum[k][best]) best = c;
    }
    region_label[k] = static_cast<std::uint8_t>(best);
    region_confidence[k] = static_cast<float>(sum[k][best] / weight[k]);
    ++out.regions_voted;
  }
  for (std::size_t s = 0; s < n; ++s) {
    const auto r = static_cast<std::size_t>(regions.segment_region[s]);
    if (region_label[r] == kVoidLabel) continue;
    if (out.labels[s] != region_label[r]) ++out.segments_changed;
    out.labels[s] = region_label[r];
    out.confidence[s] = region_confidence[r];
  }
  return out;
}

void weightTableProbabilityInPlace(std::vector<ClassProbabilities>& p, float weight) {
  if (!std::isfinite(weight) || weight <= 0.0f) {
    throw Error("tables.table_weight = " + std::to_string(weight) + ": must be a positive number");
  }
  if (weight == 1.0f) return;
  constexpr int kTable = static_cast<int>(Label::Table);
  for (auto& d : p) {
    const float total = 1.0f + (weight - 1.0f) * d[kTable];
    d[kTable] *= weight;
    for (float& v : d) v /= total;
  }
}

std::vector<ClassProbabilities> weightTableProbability(std::vector<ClassProbabilities> p,
                                                       float weight) {
  weightTableProbabilityInPlace(p, weight);
  return p;
}

}  // namespace findmug
