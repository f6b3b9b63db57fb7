#include "findmug/offline/object_stage.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "findmug/common/error.hpp"
#include "findmug/features/object_features.hpp"

namespace findmug {

namespace {
int minSegments() { const char* v = std::getenv("FM_OBJ_MINSEG"); return v ? std::atoi(v) : 1; }
bool pixelWeights() { return std::getenv("FM_OBJ_PIXW") != nullptr; }
}  // namespace

ObjectRows objectRowsOf(const FrameSample& s, const SegmenterConfig& config) {
  const RegionFeatures regions = sampleRegionFeatures(s, config.regions);
  Oversegmentation segmentation;
  segmentation.width = s.width;
  segmentation.height = s.height;
  segmentation.segments.resize(s.features.features.size());
  segmentation.edges = s.edges;
  ObjectConfig objects = config.objects;
  objects.enabled = true;
  const ObjectFeatures found = computeObjectFeatures(s.features, segmentation, regions, objects);

  ObjectRows out;
  const std::size_t n = s.features.features.size();
  out.segment_row.assign(n, -1);
  std::vector<int> group_row(found.groups.size(), -1);
  for (std::size_t g = 0; g < found.groups.size(); ++g) {
    if (found.groups[g].kind != GroupKind::Object && !std::getenv("FM_OBJ_PLANES")) continue;
    group_row[g] = static_cast<int>(out.base.size());
    out.base.push_back(FeatureVector{});
    const ObjectGroup& o = found.groups[g];
    const float columns[kObjectStageColumns] = {
        o.max_height - o.min_height, o.min_height,    o.max_height,
        o.footprint_area,            o.extent_major,  o.extent_minor,
        o.top_height,                o.top_area,      o.back_rise,
        o.wall_distance,             static_cast<float>(o.segment_count)};
    out.extra.insert(out.extra.end(), columns, columns + kObjectStageColumns);
  }
  const std::size_t rows = out.base.size();
  std::vector<double> pixels(rows, 0.0);
  std::vector<std::array<double, kNumLabels>> votes(rows, std::array<double, kNumLabels>{});
  std::vector<std::array<double, kFeatureDim>> sums(rows, std::array<double, kFeatureDim>{});
  for (std::size_t k = 0; k < n; ++k) {
    const int r = group_row[static_cast<std::size_t>(found.segment_group[k])];
    out.segment_row[k] = r;
    if (r < 0) continue;
    const auto row = static_cast<std::size_t>(r);
    const double w = s.segment_pixels.empty() ? 1.0 : s.segment_pixels[k];
    pixels[row] += w;
    for (int d = 0; d < kFeatureDim; ++d) sums[row][d] += w * s.features.features[k][d];
    if (k < s.segment_labels.size() && s.segment_labels[k] < kNumLabels)
      votes[row][s.segment_labels[k]] += w;
  }
  out.labels.assign(rows, kVoidLabel);
  out.pixels.assign(pixels.begin(), pixels.end());
  for (std::size_t r = 0; r < rows; ++r) {
    for (int d = 0; d < kFeatureDim; ++d)
      out.base[r][d] = pixels[r] > 0 ? static_cast<float>(sums[r][d] / pixels[r]) : 0.0f;
    const auto best = std::max_element(votes[r].begin(), votes[r].end());
    if (*best > 0) out.labels[r] = static_cast<std::uint8_t>(best - votes[r].begin());
  }
  return out;
}

RandomForest trainObjectForest(const std::vector<const FrameSample*>& frames,
                               const SegmenterConfig& config, const ForestParams& params) {
  TrainingSet set;
  set.extra_names.assign(kObjectStageNames.begin(), kObjectStageNames.end());
  for (const FrameSample* s : frames) {
    const ObjectRows rows = objectRowsOf(*s, config);
    for (std::size_t r = 0; r < rows.base.size(); ++r) {
      if (rows.labels[r] >= kNumLabels) continue;
      if (rows.extra[r * kObjectStageColumns + 10] < static_cast<float>(minSegments())) continue;
      if (pixelWeights()) set.weights.push_back(rows.pixels[r]);
      set.features.push_back(rows.base[r]);
      set.extra.insert(set.extra.end(), rows.extra.begin() + static_cast<std::ptrdiff_t>(r * kObjectStageColumns),
                       rows.extra.begin() + static_cast<std::ptrdiff_t>((r + 1) * kObjectStageColumns));
      set.labels.push_back(rows.labels[r]);
    }
  }
  if (std::getenv("FM_OBJ_DEBUG")) {
    int h[kNumLabels] = {};
    for (auto l : set.labels) ++h[l];
    std::fprintf(stderr, "object forest: %zu rows:", set.labels.size());
    for (int c = 0; c < kNumLabels; ++c) std::fprintf(stderr, " %s %d", labelName(static_cast<std::uint8_t>(c)).data(), h[c]);
    std::fprintf(stderr, "\n");
  }
  if (set.labels.empty()) throw Error("trainObjectForest: no labelled object candidate in the frames");
  return RandomForest::train(set, params);
}

void fuseObjectPosterior(const RandomForest& object_forest, const FrameSample& s,
                         const SegmenterConfig& config, float weight,
                         std::vector<ClassProbabilities>& probabilities) {
  const ObjectRows rows = objectRowsOf(s, config);
  std::vector<ClassProbabilities> answers(rows.base.size());
  std::vector<float> row;
  for (std::size_t r = 0; r < rows.base.size(); ++r) {
    row.assign(rows.base[r].begin(), rows.base[r].end());
    row.insert(row.end(), rows.extra.begin() + static_cast<std::ptrdiff_t>(r * kObjectStageColumns),
               rows.extra.begin() + static_cast<std::ptrdiff_t>((r + 1) * kObjectStageColumns));
    answers[r] = object_forest.predict(row);
    if (std::getenv("FM_OBJ_ORACLE") && rows.labels[r] < kNumLabels) {
      answers[r].fill(0.0f);
      answers[r][rows.labels[r]] = 1.0f;
    }
  }
  if (std::getenv("FM_OBJ_AVG")) {
    std::vector<std::array<double, kNumLabels>> sum(rows.base.size(), std::array<double, kNumLabels>{});
    for (std::size_t k = 0; k < probabilities.size(); ++k) {
      const int r = rows.segment_row[k];
      if (r < 0) continue;
      const double w = s.segment_pixels.empty() ? 1.0 : s.segment_pixels[k];
      const bool geo = std::getenv("FM_OBJ_GEO") != nullptr;
      for (int c = 0; c < kNumLabels; ++c)
        sum[static_cast<std::size_t>(r)][c] +=
            geo ? w * std::log(probabilities[k][c] + 1e-3) : w * probabilities[k][c];
    }
    if (std::getenv("FM_OBJ_GEO")) {
      for (std::size_t r = 0; r < rows.base.size(); ++r) {
        double mx = -1e300;
        for (double v : sum[r]) mx = std::max(mx, v);
        for (auto& v : sum[r]) v = std::exp((v - mx) / std::max(1.0, static_cast<double>(rows.pixels[r])));
      }
    }
    for (std::size_t r = 0; r < rows.base.size(); ++r) {
      double t = 0;
      for (double v : sum[r]) t += v;
      for (int c = 0; c < kNumLabels; ++c) answers[r][c] = t > 0 ? static_cast<float>(sum[r][c] / t) : 0.0f;
    }
  }
  for (std::size_t k = 0; k < probabilities.size(); ++k) {
    const int r = rows.segment_row[k];
    if (r < 0) continue;
    if (rows.extra[static_cast<std::size_t>(r) * kObjectStageColumns + 10] <
        static_cast<float>(minSegments()))
      continue;
    for (int c = 0; c < kNumLabels; ++c)
      probabilities[k][c] = (1 - weight) * probabilities[k][c] +
                            weight * answers[static_cast<std::size_t>(r)][c];
  }
}

}  // namespace findmug
